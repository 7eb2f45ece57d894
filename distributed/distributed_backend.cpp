#include "distributed_backend.h"

#include <chrono>
#include <stdexcept>
#include <string>

#include "continuous_step.h"
#include "exact_sum.h"
#include "halo_exchange.h"

namespace snow::dist {

std::string distributedSeasonRefusal(const SeasonConfig& c) {
  const ModelParameters& p = c.params;
  if (p.avalancheRatePerKm2PerDay > 0.0 || !c.userAvalanches.empty()) return "avalanches";
  if ((p.skiersPerHour > 0.0 && p.skiHoursPerDay > 0.0) || !c.userSkiers.empty()) return "skiers";
  if (c.bedforms) return "wind bedforms";
  if (c.skiTracks) return "the ski-track texture";
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

void DistributedBackend::upload(const SnowState& s) {
  checkLocalGrid(s.spec);
  spec_ = s.spec;
  local_->upload(s);
}

void DistributedBackend::uploadTaking(SnowState& s) {
  checkLocalGrid(s.spec);
  spec_ = s.spec;
  local_->uploadTaking(s);
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
  auto evolved = [](FieldRole r) { return r == FieldRole::Evolved || r == FieldRole::Record; };
  if (powderOnly) bytesSent_ += exchangeHalo(comm_, d_, plan_, field(SnowField::powderM), sizeof(float));
  else bytesSent_ += exchangeBackendHalos(comm_, d_, plan_, *local_, evolved);
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
  local_->snowfall(a);
  refreshHalo();
  return deltaVolume();
}

double DistributedBackend::melt(const MeltArgs& a) {
  fireBeforeWrite();
  local_->melt(a);
  refreshHalo();
  return deltaVolume();
}

// Powder diffusion writes the powder alone, whose halo its last substep's hook has refreshed.
void DistributedBackend::powderDiffusion(const PowderDiffusionArgs& a) {
  fireBeforeWrite();
  local_->powderDiffusion(a);
}

void DistributedBackend::windTransport(const WindTransportArgs& a) {
  fireBeforeWrite();
  local_->windTransport(a);
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
  local_->applyEdit(a, local);  // per cell: the halo's cells come out as their owners' (no refresh)
  return deltaVolume();
}

void DistributedBackend::stabilityChange(const StabilityArgs& a) {
  fireBeforeWrite();
  local_->stabilityChange(a);
  refreshHalo();
}

double DistributedBackend::layerSum(SnowField layer) {
  return exactSum(comm_, d_, static_cast<const float*>(field(layer)), static_cast<const uint8_t*>(field(SnowField::validCell)));
}

LayerTotals DistributedBackend::totals() {
  const double area = spec_.cellAreaM2();
  LayerTotals t;
  t.compactedM3 = layerSum(SnowField::compactedM) * area;
  t.stableM3 = layerSum(SnowField::stableM) * area;
  t.unstableM3 = layerSum(SnowField::unstableM) * area;
  t.powderM3 = layerSum(SnowField::powderM) * area;
  return t;
}

float DistributedBackend::maxTemperatureBaseC() {
  return exactMax(comm_, d_, static_cast<const float*>(field(SnowField::temperatureBaseC)),
                  static_cast<const uint8_t*>(field(SnowField::validCell)));
}

}  // namespace snow::dist
