#include "local_state.h"

#include <stdexcept>
#include <string>
#include <vector>

#include "halo_exchange.h"

namespace snow::dist {

void cutFields(const SnowState& whole, const CellRect& cells, const std::function<bool(FieldRole)>& pick, SnowState& local) {
#define SNOW_CUT_FIELD(member, view, Element, role, access, fill)                                      \
  if (pick(FieldRole::role) && whole.member.size() == whole.spec.cellCount() && whole.member.size() > 0) \
    local.member = gridWindow(whole.member, cells);
  SNOW_STATE_FIELDS(SNOW_CUT_FIELD)
#undef SNOW_CUT_FIELD
}

SnowState cutLocalState(const SnowState& whole, const CellRect& cells) {
  SnowState local;
  local.spec = windowSpec(whole.spec, cells);
  cutFields(whole, cells, [](FieldRole) { return true; }, local);
  return local;
}

SnowState cutLocalState(SnowState&& whole, const CellRect& cells) {
  SnowState local;
  local.spec = windowSpec(whole.spec, cells);
#define SNOW_TAKE_FIELD(member, view, Element, role, access, fill)                     \
  if (whole.member.size() == whole.spec.cellCount() && whole.member.size() > 0) { \
    local.member = gridWindow(whole.member, cells);                                    \
    whole.member = Grid<Element>();                                                    \
  }
  SNOW_STATE_FIELDS(SNOW_TAKE_FIELD)
#undef SNOW_TAKE_FIELD
  return local;
}

SnowState wholeLike(const SnowState& local, const GridSpec& spec) {
  SnowState whole;
  whole.spec = spec;
#define SNOW_WHOLE_FIELD(member, view, Element, role, access, fill) \
  if (local.member.size() > 0) whole.member.resize(spec.width, spec.height);
  SNOW_STATE_FIELDS(SNOW_WHOLE_FIELD)
#undef SNOW_WHOLE_FIELD
  return whole;
}

namespace {
// One field of gatherOwned: `root` takes each rank's owned block in turn (its own copied).
template <class T>
void gatherField(const Communicator& comm, const Decomposition& d, const Grid<T>& local, Grid<T>& whole, int root, const char* name) {
  const int self = comm.rank();
  const CellRect at = d.local(self);
  if (local.size() != at.cells())
    throw std::invalid_argument(std::string("gatherOwned: rank ") + std::to_string(self) + "'s " + name + " is not its local grid");
  auto ownedBlock = [&](const CellRect& o) {
    std::vector<T> block(o.cells());
    copyCells(o, at, local.data(), o, block.data(), sizeof(T));
    return block;
  };
  if (self != root) {
    const std::vector<T> block = ownedBlock(d.owned(self));
    comm.exchange({{root, block.data(), block.size() * sizeof(T)}}, {});
    return;
  }
  if (whole.size() != static_cast<size_t>(d.width) * d.height)
    throw std::invalid_argument(std::string("gatherOwned: the whole state has no ") + name + " grid of the decomposition's size");
  for (int peer = 0; peer < d.ranks(); ++peer) {
    const CellRect o = d.owned(peer);
    std::vector<T> block = peer == root ? ownedBlock(o) : std::vector<T>(o.cells());
    if (peer != root) comm.exchange({}, {{peer, block.data(), block.size() * sizeof(T)}});
    copyCells(o, o, block.data(), CellRect{0, 0, d.width, d.height}, whole.data(), sizeof(T));
  }
}
}  // namespace

void gatherOwned(const Communicator& comm, const Decomposition& d, const SnowState& local, SnowState& whole, int root) {
#define SNOW_GATHER_FIELD(member, view, Element, role, access, fill) \
  if (local.member.size() > 0) gatherField(comm, d, local.member, whole.member, root, #member);
  SNOW_STATE_FIELDS(SNOW_GATHER_FIELD)
#undef SNOW_GATHER_FIELD
}

void refreshHalos(const Communicator& comm, const Decomposition& d, SnowState& local) {
  const HaloPlan plan = haloPlan(d, comm.rank());
  const size_t cells = d.local(comm.rank()).cells();
#define SNOW_REFRESH_FIELD(member, view, Element, role, access, fill)                                                   \
  if (local.member.size() > 0 && local.member.size() != cells)                                                          \
    throw std::invalid_argument("refreshHalos: rank " + std::to_string(comm.rank()) + "'s " #member " is not its local grid"); \
  if (local.member.size() > 0) exchangeHalo(comm, d, plan, local.member.data(), sizeof(Element));
  SNOW_STATE_FIELDS(SNOW_REFRESH_FIELD)
#undef SNOW_REFRESH_FIELD
}

}  // namespace snow::dist
