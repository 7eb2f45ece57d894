#include "host_like_a_device.h"

#include "core/exec_backend.h"
#include "core/serial_exec.h"

namespace snow::test {
namespace {

struct HostLikeADevice : SerialExec {
  static constexpr bool kDevice = true;
  template <class T>
  void upload(Buffer<T>& b, const std::vector<T>& host) {
    b.values() = host;
    b.values().shrink_to_fit();
  }
};

}  // namespace

std::unique_ptr<SnowBackend> createHostLikeADeviceBackend() { return std::make_unique<ExecBackend<HostLikeADevice>>(); }

}  // namespace snow::test
