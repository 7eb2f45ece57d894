#include "window_gather.h"

#include <vector>

namespace snow::dist {

size_t gatherWindow(const Communicator& comm, const Decomposition& d, const void* local, size_t elementBytes, const CellRect& want, void* held) {
  const std::vector<double> wants = comm.allGather({double(want.x0), double(want.y0), double(want.x1), double(want.y1)});
  const int self = comm.rank();
  const CellRect mine = d.owned(self), myLocal = d.local(self);
  std::vector<std::vector<char>> out(comm.size()), in(comm.size());
  std::vector<Communicator::Send> sends;
  std::vector<Communicator::Receive> receives;
  size_t sent = 0;
  for (int peer = 0; peer < comm.size(); ++peer) {
    const CellRect theirs{int(wants[4 * peer]), int(wants[4 * peer + 1]), int(wants[4 * peer + 2]), int(wants[4 * peer + 3])};
    const CellRect give = mine.intersect(theirs), take = d.owned(peer).intersect(want);
    if (peer == self) {
      if (!give.empty()) copyCells(give, myLocal, local, want, held, elementBytes);
      continue;
    }
    if (!give.empty()) {
      out[peer].resize(give.cells() * elementBytes);
      copyCells(give, myLocal, local, give, out[peer].data(), elementBytes);
      sends.push_back({peer, out[peer].data(), out[peer].size()});
      sent += out[peer].size();
    }
    if (!take.empty()) {
      in[peer].resize(take.cells() * elementBytes);
      receives.push_back({peer, in[peer].data(), in[peer].size()});
    }
  }
  comm.exchange(sends, receives);
  for (int peer = 0; peer < comm.size(); ++peer)
    if (const CellRect take = d.owned(peer).intersect(want); peer != self && !take.empty())
      copyCells(take, take, in[peer].data(), want, held, elementBytes);
  return sent;
}

}  // namespace snow::dist
