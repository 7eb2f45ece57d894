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
  if (!c.edits.empty()) return "timeline edits";
  if (c.updateStaticFields) return "static fields that change with the day (a wind timeline, daily sun)";
  return "";
}

DistributedBackend::DistributedBackend(std::unique_ptr<SnowBackend> local, const Communicator& comm, const Decomposition& d,
                                       bool measureWaits)
    : local_(std::move(local)), comm_(comm), d_(d), plan_(haloPlan(d, comm.rank())), measureWaits_(measureWaits) {
  if (d.halo < kContinuousHalo)
    throw std::invalid_argument("DistributedBackend: a halo of " + std::to_string(d.halo) + " cells, where the season needs " +
                                std::to_string(kContinuousHalo));
  local_->afterEachPowderSubstep([this] { refreshHalo(true); });
}

void DistributedBackend::notYet(const char* what) {
  throw std::logic_error(std::string("a season across ranks does not run ") + what + " yet (docs/distributed.md)");
}

void DistributedBackend::upload(const SnowState& s) {
  spec_ = s.spec;
  local_->upload(s);
}

void DistributedBackend::uploadTaking(SnowState& s) {
  spec_ = s.spec;
  local_->uploadTaking(s);
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
  if (powderOnly) bytesSent_ += exchangeHalo(comm_, d_, plan_, local_->hostField(SnowField::powderM), sizeof(float));
  else bytesSent_ += exchangeBackendHalos(comm_, d_, plan_, *local_, [](FieldRole r) { return r == FieldRole::Evolved || r == FieldRole::Record; });
  exchangeS_ += since(t0);
}

double DistributedBackend::deltaVolume() {
  const auto* delta = static_cast<const float*>(local_->hostScratch(ScratchField::delta));
  const auto* valid = static_cast<const uint8_t*>(local_->hostField(SnowField::validCell));
  if (!delta || !valid) throw std::logic_error("DistributedBackend: the local backend's fields are not in host memory");
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

void DistributedBackend::powderDiffusion(const PowderDiffusionArgs& a) {
  fireBeforeWrite();
  local_->powderDiffusion(a);
  refreshHalo();
}

void DistributedBackend::windTransport(const WindTransportArgs& a) {
  fireBeforeWrite();
  local_->windTransport(a);
  refreshHalo();
}

void DistributedBackend::stabilityChange(const StabilityArgs& a) {
  fireBeforeWrite();
  local_->stabilityChange(a);
  refreshHalo();
}

double DistributedBackend::layerSum(SnowField layer) {
  const auto* values = static_cast<const float*>(local_->hostField(layer));
  const auto* valid = static_cast<const uint8_t*>(local_->hostField(SnowField::validCell));
  if (!values || !valid) throw std::logic_error("DistributedBackend: the local backend's fields are not in host memory");
  return exactSum(comm_, d_, values, valid);
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
  const auto* values = static_cast<const float*>(local_->hostField(SnowField::temperatureBaseC));
  const auto* valid = static_cast<const uint8_t*>(local_->hostField(SnowField::validCell));
  if (!values || !valid) throw std::logic_error("DistributedBackend: the local backend's fields are not in host memory");
  return exactMax(comm_, d_, values, valid);
}

}  // namespace snow::dist
