#include "whole_replica.h"

#include <stdexcept>
#include <string>
#include <vector>

namespace snow::dist {

size_t allGatherOwned(const Communicator& comm, const Decomposition& d, const void* local, void* whole, size_t elementBytes) {
  const int self = comm.rank();
  const CellRect all{0, 0, d.width, d.height}, mine = d.owned(self);
  std::vector<unsigned char> block(mine.cells() * elementBytes);
  copyCells(mine, d.local(self), local, mine, block.data(), elementBytes);
  copyCells(mine, mine, block.data(), all, whole, elementBytes);
  std::vector<std::vector<unsigned char>> theirs(static_cast<size_t>(d.ranks()));
  std::vector<Communicator::Send> sends;
  std::vector<Communicator::Receive> receives;
  for (int peer = 0; peer < d.ranks(); ++peer) {
    if (peer == self) continue;
    theirs[peer].resize(d.owned(peer).cells() * elementBytes);
    sends.push_back({peer, block.data(), block.size()});
    receives.push_back({peer, theirs[peer].data(), theirs[peer].size()});
  }
  comm.exchange(sends, receives);
  for (int peer = 0; peer < d.ranks(); ++peer)
    if (peer != self) copyCells(d.owned(peer), d.owned(peer), theirs[peer].data(), all, whole, elementBytes);
  return block.size() * sends.size();
}

namespace {
// Calls f(name, local's field, replica's field, element bytes) for each field `pick` accepts
// that the two hold.
template <class F>
void forEachSharedField(SnowBackend& local, SnowBackend& replica, const std::function<bool(FieldRole)>& pick, F&& f) {
  if (!local.hostField(SnowField::bedrockM) || !replica.hostField(SnowField::bedrockM))
    throw std::logic_error("the whole grid's replica and the local grid must both be in host memory");
#define SNOW_REPLICA_FIELD(member, view, Element, role, access, fill)                                       \
  if (pick(FieldRole::role)) {                                                                             \
    void* l = local.hostField(SnowField::member);                                                          \
    void* r = replica.hostField(SnowField::member);                                                        \
    if ((l == nullptr) != (r == nullptr))                                                                  \
      throw std::logic_error(std::string("the whole grid's replica and the local grid disagree on ") + #member); \
    if (l) f(l, r, sizeof(Element));                                                                       \
  }
  SNOW_STATE_FIELDS(SNOW_REPLICA_FIELD)
#undef SNOW_REPLICA_FIELD
}
}  // namespace

size_t gatherIntoReplica(const Communicator& comm, const Decomposition& d, SnowBackend& local, SnowBackend& replica,
                         const std::function<bool(FieldRole)>& pick) {
  size_t sent = 0;
  forEachSharedField(local, replica, pick, [&](void* l, void* r, size_t bytes) { sent += allGatherOwned(comm, d, l, r, bytes); });
  return sent;
}

void cutFromReplica(const Decomposition& d, int rank, SnowBackend& replica, SnowBackend& local, const std::function<bool(FieldRole)>& pick) {
  const CellRect all{0, 0, d.width, d.height}, at = d.local(rank);
  forEachSharedField(local, replica, pick, [&](void* l, void* r, size_t bytes) { copyCells(at, all, r, at, l, bytes); });
}

}  // namespace snow::dist
