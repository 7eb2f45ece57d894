#include "halo_exchange.h"

#include <stdexcept>
#include <vector>

#include "core/snow_state.h"

namespace snow::dist {

size_t exchangeHalo(const Communicator& comm, const Decomposition& d, const HaloPlan& plan, void* local, size_t elementBytes) {
  const CellRect at = d.local(comm.rank());
  std::vector<std::vector<char>> out(plan.sends.size()), in(plan.receives.size());
  std::vector<Communicator::Send> sends;
  std::vector<Communicator::Receive> receives;
  size_t sent = 0;
  for (size_t k = 0; k < plan.sends.size(); ++k) {
    const HaloTransfer& t = plan.sends[k];
    out[k].resize(t.cells.cells() * elementBytes);
    copyCells(t.cells, at, local, t.cells, out[k].data(), elementBytes);
    sends.push_back({t.peer, out[k].data(), out[k].size()});
    sent += out[k].size();
  }
  for (size_t k = 0; k < plan.receives.size(); ++k) {
    in[k].resize(plan.receives[k].cells.cells() * elementBytes);
    receives.push_back({plan.receives[k].peer, in[k].data(), in[k].size()});
  }
  comm.exchange(sends, receives);
  for (size_t k = 0; k < plan.receives.size(); ++k) {
    const CellRect& cells = plan.receives[k].cells;
    copyCells(cells, cells, in[k].data(), at, local, elementBytes);
  }
  return sent;
}

size_t exchangeBackendHalos(const Communicator& comm, const Decomposition& d, const HaloPlan& plan, SnowBackend& backend,
                            const std::function<bool(FieldRole)>& pick) {
  // The bedrock is held by every backend: without it in host memory, the fields are on a device.
  if (!backend.hostField(SnowField::bedrockM))
    throw std::logic_error("exchangeBackendHalos: backend '" + backend.name() + "' holds its fields on a device");
  size_t sent = 0;
#define SNOW_EXCHANGE_FIELD(member, view, Element, role, access, fill)                            \
  if (pick(FieldRole::role)) {                                                                    \
    if (void* data = backend.hostField(SnowField::member)) {                                      \
      sent += exchangeHalo(comm, d, plan, data, sizeof(Element));                                 \
    }                                                                                             \
  }
  SNOW_STATE_FIELDS(SNOW_EXCHANGE_FIELD)
#undef SNOW_EXCHANGE_FIELD
  return sent;
}

}  // namespace snow::dist
