// SnowBackend implemented once over any Exec: the Exec supplies storage (host vectors or
// device buffers), forEachCell / forEachCellOfColour and fixed-order reductions; this class
// owns the fields and runs the step functions of steps.h. Included by core/cpu_backend.cpp and
// by the CUDA backend's .cu file, so it must stay free of TBB and CUDA headers.
#pragma once
#include <string>
#include <utility>
#include <vector>

#include "backend.h"
#include "steps.h"

namespace snow {

template <class Exec>
class ExecBackend final : public SnowBackend {
 public:
  template <class... ExecArgs>
  explicit ExecBackend(ExecArgs&&... args) : exec_(std::forward<ExecArgs>(args)...) {}

  std::string name() const override { return exec_.name(); }

  void upload(const SnowState& s) override {
    spec_ = s.spec;
    exec_.upload(bedrock_, s.bedrockM.values());
    exec_.upload(compacted_, s.compactedM.values());
    exec_.upload(stable_, s.stableM.values());
    exec_.upload(unstable_, s.unstableM.values());
    exec_.upload(powder_, s.powderM.values());
    exec_.upload(moving_, s.snowMoving.values());
    exec_.upload(windScour_, s.windScourM.values());
    exec_.upload(windDeposit_, s.windDepositM.values());
    exec_.upload(melted_, s.meltedM.values());
    exec_.upload(valid_, s.validCell.values());
    exec_.upload(delta_, std::vector<float>(s.spec.cellCount(), 0.f));
    exec_.upload(surfaceSlope_, std::vector<float>(s.spec.cellCount(), 0.f));
    exec_.upload(scratchSurface_, std::vector<float>(s.spec.cellCount(), 0.f));
    exec_.upload(scratchPowder_, std::vector<float>(s.spec.cellCount(), 0.f));
    uploadStaticFields(s);
  }

  void uploadStaticFields(const SnowState& s) override {
    exec_.upload(exposure_, s.exposureHours.values());
    exec_.upload(temperatureBase_, s.temperatureBaseC.values());
    exec_.upload(windX_, s.windXMps.values());
    exec_.upload(windY_, s.windYMps.values());
    exec_.upload(windEffectZ_, s.windEffectZM.values());
    exec_.upload(windLoading_, s.windLoadingMps2.values());
  }

  void download(SnowState& s) override {
    exec_.download(compacted_, s.compactedM.values());
    exec_.download(stable_, s.stableM.values());
    exec_.download(unstable_, s.unstableM.values());
    exec_.download(powder_, s.powderM.values());
    exec_.download(moving_, s.snowMoving.values());
    exec_.download(windScour_, s.windScourM.values());
    exec_.download(windDeposit_, s.windDepositM.values());
    exec_.download(melted_, s.meltedM.values());
  }

  double snowfall(const SnowfallArgs& a) override { return runSnowfall(exec_, view(), a); }
  double melt(const MeltArgs& a) override { return runMelt(exec_, view(), a); }
  void stabilityChange(const StabilityArgs& a) override { runStability(exec_, view(), a); }
  void windTransport(const WindTransportArgs& a) override {
    runWindTransport(exec_, view(), a);
    exec_.finish();
  }
  void powderDiffusion(const PowderDiffusionArgs& a) override {
    runPowderDiffusion(exec_, view(), a);
    exec_.finish();
  }

  LayerTotals totals() override {
    const double area = spec_.cellAreaM2();
    const int w = spec_.width, h = spec_.height;
    LayerTotals t;
    t.compactedM3 = exec_.sum(compacted_.data(), valid_.data(), w, h) * area;
    t.stableM3 = exec_.sum(stable_.data(), valid_.data(), w, h) * area;
    t.unstableM3 = exec_.sum(unstable_.data(), valid_.data(), w, h) * area;
    t.powderM3 = exec_.sum(powder_.data(), valid_.data(), w, h) * area;
    return t;
  }

  float maxTemperatureBaseC() override {
    return exec_.maxValue(temperatureBase_.data(), valid_.data(), spec_.width, spec_.height);
  }

  Exec& exec() { return exec_; }

 private:
  SnowFieldsView view() {
    SnowFieldsView v;
    v.width = spec_.width;
    v.height = spec_.height;
    v.cellSizeXM = static_cast<float>(spec_.cellSizeXM);
    v.cellSizeYM = static_cast<float>(spec_.cellSizeYM);
    v.bedrock = bedrock_.data();
    v.compacted = compacted_.data();
    v.stable = stable_.data();
    v.unstable = unstable_.data();
    v.powder = powder_.data();
    v.moving = moving_.data();
    v.valid = valid_.data();
    v.exposure = exposure_.data();
    v.temperatureBase = temperatureBase_.data();
    v.windX = windX_.data();
    v.windY = windY_.data();
    v.windEffectZ = windEffectZ_.data();
    v.windLoading = windLoading_.data();
    v.windScour = windScour_.data();
    v.windDeposit = windDeposit_.data();
    v.melted = melted_.data();
    v.delta = delta_.data();
    v.surfaceSlope = surfaceSlope_.data();
    v.scratchSurface = scratchSurface_.data();
    v.scratchPowder = scratchPowder_.data();
    return v;
  }

  Exec exec_;
  GridSpec spec_;
  typename Exec::template Buffer<float> bedrock_, compacted_, stable_, unstable_, powder_;
  typename Exec::template Buffer<uint8_t> moving_, valid_;
  typename Exec::template Buffer<float> exposure_, temperatureBase_, windX_, windY_, windEffectZ_, delta_, surfaceSlope_, scratchSurface_, scratchPowder_;
  typename Exec::template Buffer<float> windLoading_, windScour_, windDeposit_, melted_;
};

}  // namespace snow
