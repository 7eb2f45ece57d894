#include "distributed_backend.h"

#include <chrono>
#include <stdexcept>
#include <string>

#include "continuous_step.h"
#include "core/grid_window.h"
#include "exact_sum.h"
#include "halo_exchange.h"
#include "whole_replica.h"

namespace snow::dist {

namespace {
// The first of the season's phenomena that run on the whole grid's replica, or null.
const char* replicatedPhenomenon(const SeasonConfig& c) {
  const ModelParameters& p = c.params;
  if (p.avalancheRatePerKm2PerDay > 0.0 || !c.userAvalanches.empty()) return "avalanches";
  if ((p.skiersPerHour > 0.0 && p.skiHoursPerDay > 0.0) || !c.userSkiers.empty()) return "skiers";
  if (c.bedforms) return "wind bedforms";
  return nullptr;
}
}  // namespace

bool seasonNeedsReplica(const SeasonConfig& c) { return replicatedPhenomenon(c) != nullptr; }

std::string distributedSeasonRefusal(const SeasonConfig& c, bool replicated) {
  if (replicated) return c.eventTerrain ? "" : "a replica of the whole grid but no SeasonConfig::eventTerrain";
  if (const char* phenomenon = replicatedPhenomenon(c)) return phenomenon;
  if (c.skiTracks) return "the ski-track texture";
  if (c.eventTerrain) return "SeasonConfig::eventTerrain but no replica of the whole grid";
  return "";
}

DistributedBackend::DistributedBackend(std::unique_ptr<SnowBackend> local, const Communicator& comm, const Decomposition& d,
                                       bool measureWaits)
    : local_(std::move(local)), comm_(comm), d_(d), plan_(haloPlan(d, comm.rank())), measureWaits_(measureWaits) {
  if (comm.size() != d.ranks())
    throw std::invalid_argument("DistributedBackend: a decomposition of " + std::to_string(d.ranks()) + " ranks run on " +
                                std::to_string(comm.size()));
  if (d.halo < kContinuousHalo)
    throw std::invalid_argument("DistributedBackend: a halo of " + std::to_string(d.halo) + " cells, where the season needs " +
                                std::to_string(kContinuousHalo));
  local_->afterEachPowderSubstep([this] { refreshHalo(true); });
}

void DistributedBackend::notYet(const char* what) {
  throw std::logic_error(std::string("a season across ranks does not run ") + what + " yet (docs/distributed.md)");
}

// The halo exchange and the sums index the local grid by the decomposition: it must be that one.
void DistributedBackend::checkLocalGrid(const GridSpec& spec) const {
  const CellRect l = d_.local(comm_.rank());
  if (spec.width != l.width() || spec.height != l.height())
    throw std::invalid_argument("DistributedBackend: a " + std::to_string(spec.width) + " x " + std::to_string(spec.height) +
                                " state uploaded on rank " + std::to_string(comm_.rank()) + ", whose local grid is " +
                                std::to_string(l.width()) + " x " + std::to_string(l.height()));
}

void DistributedBackend::replicateEvents(std::unique_ptr<SnowBackend> replica, SnowState& whole) {
  if (whole.spec.width != d_.width || whole.spec.height != d_.height)
    throw std::invalid_argument("DistributedBackend::replicateEvents: the whole state is not the decomposition's grid");
  replica_ = std::move(replica);
  whole_ = &whole;
  replicaUploaded_ = false;
}

void DistributedBackend::upload(const SnowState& s) {
  checkLocalGrid(s.spec);
  spec_ = s.spec;
  // A second upload would have to reset the replica's avalanche, skier and bedform state too.
  if (replica_) throw std::logic_error("DistributedBackend: a season with the whole grid's replica uploads once, by uploadTaking");
  local_->upload(s);
}

void DistributedBackend::uploadTaking(SnowState& s) {
  checkLocalGrid(s.spec);
  spec_ = s.spec;
  if (replica_) uploadReplica(s);
  local_->uploadTaking(s);
}

// The whole state's snow to the replica, with the record fields the rank's season keeps (as its
// state holds them now: zero where the whole state has none).
void DistributedBackend::uploadReplica(const SnowState& local) {
  SnowState& w = *whole_;
#define SNOW_KEEP_RECORD(member, view, Element, role, access, fill)   \
  if constexpr (FieldRole::role == FieldRole::Record) {               \
    if (local.member.size() == 0) w.member = Grid<Element>();         \
    else if (w.member.size() == 0) w.member.resize(w.spec.width, w.spec.height, fill); \
  }
  SNOW_STATE_FIELDS(SNOW_KEEP_RECORD)
#undef SNOW_KEEP_RECORD
  replica_->uploadTaking(w);
  replicaUploaded_ = true;
  current_ = Current::Both;
}

// The replica's steps (an avalanche's, a skier batch, bedforms) into the local grid.
void DistributedBackend::localUpToDate() {
  if (current_ != Current::Replica) return;
  cutFromReplica(d_, comm_.rank(), *replica_, *local_, downloadedWithState);
  current_ = Current::Both;
}

// The local grids' steps into the replica, on every rank at once: the ranks' events are the same.
SnowBackend& DistributedBackend::replicaUpToDate(const char* what) {
  if (!replica_ || !replicaUploaded_) notYet(what);
  if (current_ == Current::Local) {
    using Clock = std::chrono::steady_clock;
    const auto t0 = Clock::now();
    replicaBytes_ += gatherIntoReplica(comm_, d_, *local_, *replica_, downloadedWithState);
    exchangeS_ += std::chrono::duration<double>(Clock::now() - t0).count();
    ++replicaGathers_;
    current_ = Current::Both;
  }
  return *replica_;
}

void DistributedBackend::uploadStaticFields(const SnowState& s) {
  staticFieldsUploaded();
  local_->uploadStaticFields(s);
  if (replica_ && replicaUploaded_) replica_->uploadStaticFields(*whole_);
}

// A frame's (or the season's end's) bedform cohesion, cut from the replica once bedforms ran.
void DistributedBackend::addBedformCohesion(SnowState& s) {
  Grid<float> whole;
  if (!replica_ || !replicaUploaded_ || !replica_->bedformCohesion(whole)) return;
  const CellRect at = d_.local(comm_.rank());
  s.bedformCohesion = gridWindow(whole, at.x0, at.y0, at.width(), at.height());
}

void DistributedBackend::download(SnowState& s) {
  localUpToDate();
  local_->download(s);
  addBedformCohesion(s);
}

void DistributedBackend::downloadGiving(SnowState& s) {
  localUpToDate();
  // The replica stays the snow's record after the local grids give theirs away (the season's end
  // fades the ski-track texture by it).
  if (replica_ && replicaUploaded_) replicaUpToDate("avalanches and skiers");
  local_->downloadGiving(s);
  addBedformCohesion(s);
}

// Writable: the replica is brought up to date from the local grids before its next step.
void* DistributedBackend::hostField(SnowField f) {
  localUpToDate();
  wroteLocal();
  return local_->hostField(f);
}

void* DistributedBackend::hostScratch(ScratchField f) { return local_->hostScratch(f); }

void DistributedBackend::releaseRouteMap() {
  if (replica_) replica_->releaseRouteMap();
}

void DistributedBackend::releaseScratch(bool avalancheFields) {
  local_->releaseScratch(avalancheFields);
  if (replica_) replica_->releaseScratch(avalancheFields);
}

bool DistributedBackend::hostSnowLayers(const float* layers[4]) {
  return replicaUpToDate("avalanches and skiers").hostSnowLayers(layers);
}

void DistributedBackend::readCells(int x0, int y0, int cols, int rows, std::vector<float>& depth, std::vector<float>& unstable) {
  replicaUpToDate("avalanches and skiers").readCells(x0, y0, cols, rows, depth, unstable);
}

void DistributedBackend::downloadBox(SnowBox& box, bool peaks) { replicaUpToDate("avalanches").downloadBox(box, peaks); }

BedformStepReport DistributedBackend::bedformStep(const BedformArgs& a) {
  fireBeforeWrite();
  SnowBackend& replica = replicaUpToDate("wind bedforms");
  const BedformStepReport r = replica.bedformStep(a);
  current_ = Current::Replica;
  // The step's domain, which the rank's wind transport and powder diffusion leave.
  std::vector<uint8_t> whole, mine;
  if (replica.bedformDomain(whole)) {
    const CellRect at = d_.local(comm_.rank());
    mine.resize(at.cells());
    copyCells(at, CellRect{0, 0, d_.width, d_.height}, whole.data(), at, mine.data(), sizeof(uint8_t));
    local_->useBedformDomain(mine);
  }
  return r;
}

// The replica's own field (no snow): read without a gather, which every rank would have to join.
bool DistributedBackend::bedformCohesion(Grid<float>& out) {
  if (!replica_ || !replicaUploaded_) notYet("wind bedforms");
  return replica_->bedformCohesion(out);
}

void DistributedBackend::uploadRouteMap(const Grid<float>& route) { replicaUpToDate("skiers").uploadRouteMap(route); }

void DistributedBackend::skierBatch(const SkierArgs& a, std::vector<SkierAgent>& agents, std::vector<std::vector<double>>& paths) {
  fireBeforeWrite();
  replicaUpToDate("skiers").skierBatch(a, agents, paths);
  current_ = Current::Replica;
}

void DistributedBackend::avalancheRelease(const std::vector<uint8_t>& moving, const AvalancheArgs& a) {
  replicaUpToDate("avalanches").avalancheRelease(moving, a);
  current_ = Current::Replica;
}

std::vector<float> DistributedBackend::avalancheSteps(const AvalancheArgs& a, int substeps) {
  std::vector<float> stats = replicaUpToDate("avalanches").avalancheSteps(a, substeps);
  current_ = Current::Replica;
  return stats;
}

void DistributedBackend::avalancheSettle(const AvalancheArgs& a) {
  replicaUpToDate("avalanches").avalancheSettle(a);
  current_ = Current::Replica;
}

void* DistributedBackend::field(SnowField f) {
  void* data = local_->hostField(f);
  if (!data) throw std::logic_error("DistributedBackend: the local backend's fields are not in host memory");
  return data;
}

// The evolved and record fields (the field table's roles a phenomenon writes), or the powder alone
// between powder diffusion's substeps.
void DistributedBackend::refreshHalo(bool powderOnly) {
  using Clock = std::chrono::steady_clock;
  auto since = [](Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); };
  if (measureWaits_) {
    const auto t = Clock::now();
    comm_.barrier();
    waitS_ += since(t);
  }
  const auto t0 = Clock::now();
  if (powderOnly) bytesSent_ += exchangeHalo(comm_, d_, plan_, field(SnowField::powderM), sizeof(float));
  else bytesSent_ += exchangeBackendHalos(comm_, d_, plan_, *local_, downloadedWithState);
  exchangeS_ += since(t0);
}

double DistributedBackend::deltaVolume() {
  const auto* delta = static_cast<const float*>(local_->hostScratch(ScratchField::delta));
  if (!delta) throw std::logic_error("DistributedBackend: the local backend's scratch is not in host memory");
  const auto* valid = static_cast<const uint8_t*>(field(SnowField::validCell));
  return exactSum(comm_, d_, delta, valid) * static_cast<double>(static_cast<float>(spec_.cellSizeXM)) *
         static_cast<float>(spec_.cellSizeYM);
}

double DistributedBackend::snowfall(const SnowfallArgs& a) {
  fireBeforeWrite();
  localUpToDate();
  local_->snowfall(a);
  wroteLocal();
  refreshHalo();
  return deltaVolume();
}

double DistributedBackend::melt(const MeltArgs& a) {
  fireBeforeWrite();
  localUpToDate();
  local_->melt(a);
  wroteLocal();
  refreshHalo();
  return deltaVolume();
}

// Powder diffusion writes the powder alone, whose halo its last substep's hook has refreshed.
void DistributedBackend::powderDiffusion(const PowderDiffusionArgs& a) {
  fireBeforeWrite();
  localUpToDate();
  local_->powderDiffusion(a);
  wroteLocal();
}

void DistributedBackend::windTransport(const WindTransportArgs& a) {
  fireBeforeWrite();
  localUpToDate();
  local_->windTransport(a);
  wroteLocal();
  refreshHalo();
}

double DistributedBackend::applyEdit(const EditArgs& a, const std::vector<float>& weights) {
  fireBeforeWrite();
  const CellRect whole{0, 0, d_.width, d_.height}, mine = d_.local(comm_.rank());
  std::vector<float> local;
  if (!weights.empty()) {
    if (weights.size() != whole.cells())
      throw std::invalid_argument("DistributedBackend::applyEdit: " + std::to_string(weights.size()) + " weights for a grid of " +
                                  std::to_string(whole.cells()) + " cells");
    local.resize(mine.cells());
    copyCells(mine, whole, weights.data(), mine, local.data(), sizeof(float));
  }
  localUpToDate();
  local_->applyEdit(a, local);
  wroteLocal();  // per cell: the halo's cells come out as their owners' (no refresh)
  return deltaVolume();
}

void DistributedBackend::stabilityChange(const StabilityArgs& a) {
  fireBeforeWrite();
  localUpToDate();
  local_->stabilityChange(a);
  wroteLocal();
  refreshHalo();
}

double DistributedBackend::layerSum(SnowField layer) {
  return exactSum(comm_, d_, static_cast<const float*>(field(layer)), static_cast<const uint8_t*>(field(SnowField::validCell)));
}

LayerTotals DistributedBackend::totals() {
  localUpToDate();
  const double area = spec_.cellAreaM2();
  LayerTotals t;
  t.compactedM3 = layerSum(SnowField::compactedM) * area;
  t.stableM3 = layerSum(SnowField::stableM) * area;
  t.unstableM3 = layerSum(SnowField::unstableM) * area;
  t.powderM3 = layerSum(SnowField::powderM) * area;
  return t;
}

float DistributedBackend::maxTemperatureBaseC() {
  localUpToDate();
  return exactMax(comm_, d_, static_cast<const float*>(field(SnowField::temperatureBaseC)),
                  static_cast<const uint8_t*>(field(SnowField::validCell)));
}

}  // namespace snow::dist
