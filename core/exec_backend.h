// SnowBackend implemented once over any Exec: the Exec supplies storage (host vectors or
// device buffers), forEachCell and fixed-order reductions; this class
// owns the fields and runs each phenomenon's runX (core/phenomena/) over them. Included by
// core/cpu_backend.cpp and by the CUDA backend's .cu file, so it must stay free of TBB and CUDA
// headers.
#pragma once
#include <algorithm>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "backend.h"

namespace snow {

// An executor with host threads of its own for forEachHostChunk (C++17: nvcc reads this header).
template <class E, class = void>
struct HasHostChunks : std::false_type {};
template <class E>
struct HasHostChunks<E, std::void_t<decltype(&E::forEachHostChunk)>> : std::true_type {};

template <class Exec>
class ExecBackend final : public SnowBackend {
 public:
  template <class... ExecArgs>
  explicit ExecBackend(ExecArgs&&... args) : exec_(std::forward<ExecArgs>(args)...) {}

  std::string name() const override { return exec_.name(); }

  // The state's fields by their roles (snow_fields.h); the scratch fields made with the state
  // zeroed; the avalanche's and the bedforms' fields made again at their first step.
  void upload(const SnowState& s) override { uploadState(s, nullptr); }
  uint64_t stateVersion() const override { return stateVersion_; }
  void uploadTaking(SnowState& s) override { uploadState(s, &s); }

  // Static fields, and the art-direction ones the scene paints (empty buffers otherwise: null in
  // the kernels).
  void uploadStaticFields(const SnowState& s) override {
    staticFieldsUploaded();
#define SNOW_UPLOAD_STATIC(member, view, Element, role, access, fill) \
  if constexpr (uploadedWithStaticFields(FieldRole::role)) uploadField<FieldRole::role>(member##_, s.member);
    SNOW_STATE_FIELDS(SNOW_UPLOAD_STATIC)
#undef SNOW_UPLOAD_STATIC
  }

  double applyEdit(const EditArgs& a, const std::vector<float>& weights) override {
    return runEdit(exec_, view(), editWeight_, a, weights);
  }

  // The fields both the state and the backend hold (a season may keep only some record fields).
  void download(SnowState& s) override {
#define SNOW_DOWNLOAD(member, view, Element, role, access, fill) \
  if constexpr (downloadedWithState(FieldRole::role))            \
    if (s.member.size() > 0 && member##_.size() > 0) exec_.download(member##_, s.member.values());
    SNOW_STATE_FIELDS(SNOW_DOWNLOAD)
#undef SNOW_DOWNLOAD
    if (bed_.ready) {
      s.bedformCohesion.resize(spec_.width, spec_.height, 0.f);
      exec_.download(bed_.cohesion, s.bedformCohesion.values());
    }
  }

  void downloadGiving(SnowState& s) override {
    ++stateVersion_;  // the fields leave the backend until the next upload
#define SNOW_DOWNLOAD_GIVING(member, view, Element, role, access, fill)        \
  if constexpr (downloadedWithState(FieldRole::role)) {                        \
    std::vector<Element> values;                                               \
    exec_.downloadGiving(member##_, values);                                   \
    if (values.empty()) s.member = Grid<Element>(); /* a record not kept */    \
    else s.member.adopt(spec_.width, spec_.height, std::move(values));         \
  }
    SNOW_STATE_FIELDS(SNOW_DOWNLOAD_GIVING)
#undef SNOW_DOWNLOAD_GIVING
    if (bed_.ready) {
      s.bedformCohesion.resize(spec_.width, spec_.height, 0.f);
      exec_.download(bed_.cohesion, s.bedformCohesion.values());
    }
  }

  void returnState(SnowState& s) override {
    ++stateVersion_;
#define SNOW_RETURN_STATE(member, view, Element, role, access, fill) \
  if constexpr (downloadedWithState(FieldRole::role)) {              \
    exec_.uploadTaking(member##_, s.member.values());                \
    s.member = Grid<Element>();                                      \
  }
    SNOW_STATE_FIELDS(SNOW_RETURN_STATE)
#undef SNOW_RETURN_STATE
  }

  bool hostSnowLayers(const float* layers[4]) override {
    if constexpr (Exec::kDevice) {
      (void)layers;
      return false;
    } else {
      layers[0] = compactedM_.data(), layers[1] = stableM_.data(), layers[2] = unstableM_.data(), layers[3] = powderM_.data();
      return true;
    }
  }

  void* hostField(SnowField field) override {
    switch (field) {
#define SNOW_HOST_FIELD(member, view, Element, role, access, fill) \
  case SnowField::member:                                          \
    if constexpr (heldByBackend(FieldRole::role)) return hostData(member##_); \
    else return nullptr;
      SNOW_STATE_FIELDS(SNOW_HOST_FIELD)
#undef SNOW_HOST_FIELD
      case SnowField::Count: break;
    }
    return nullptr;
  }

  void* hostScratch(ScratchField field) override {
    switch (field) {
#define SNOW_HOST_SCRATCH(view, Element, extent) \
  case ScratchField::view: return hostData(view##_);
      SNOW_SCRATCH_FIELDS(SNOW_HOST_SCRATCH)
#undef SNOW_HOST_SCRATCH
      case ScratchField::Count: break;
    }
    return nullptr;
  }

  // The scratch made with the state comes back, zeroed, with the next kernel's view.
  void releaseScratch(bool avalancheFields) override {
#define SNOW_RELEASE_SCRATCH(view, Element, extent) \
  if (madeWithState(ScratchExtent::extent) || avalancheFields) freeBuffer(view##_);
    SNOW_SCRATCH_FIELDS(SNOW_RELEASE_SCRATCH)
#undef SNOW_RELEASE_SCRATCH
    scratchReleased_ = true;
    if (avalancheFields && avalancheFieldsReady_) avalancheFieldsReady_ = false, avalancheFieldsFreed_ = true;
    releaseRouteMap();
  }

  void releaseRouteMap() override {
    freeBuffer(skiers_.route), freeBuffer(skiers_.claim), freeBuffer(skiers_.agents), freeBuffer(skiers_.path);
    skiers_.hostRoute = nullptr;
  }

  void forEachHostChunk(int n, int chunk, const std::function<void(int, int)>& f) override {
    if constexpr (HasHostChunks<Exec>::value) exec_.forEachHostChunk(n, chunk, f);
    else SnowBackend::forEachHostChunk(n, chunk, f);
  }

  double snowfall(const SnowfallArgs& a) override { return runSnowfall(exec_, view(), a); }
  double melt(const MeltArgs& a) override { return runMelt(exec_, view(), a); }
  void stabilityChange(const StabilityArgs& a) override { runStability(exec_, view(), a); }
  void windTransport(const WindTransportArgs& a) override {
    runWindTransport(exec_, view(), a);
    exec_.finish();
  }
  void powderDiffusion(const PowderDiffusionArgs& a) override {
    runPowderDiffusion(exec_, view(), a, afterPowderSubstep_);
    exec_.finish();
  }

  void readCells(int x0, int y0, int cols, int rows, std::vector<float>& depth, std::vector<float>& unstable) override {
    depth.assign(static_cast<size_t>(cols) * rows, 0.f);
    unstable.assign(depth.size(), 0.f);
    std::vector<float> row(static_cast<size_t>(cols));
    for (int r = 0; r < rows; ++r) {
      const size_t offset = static_cast<size_t>(y0 + r) * spec_.width + x0;
      float* d = &depth[static_cast<size_t>(r) * cols];
      for (auto* layer : {&compactedM_, &stableM_, &unstableM_, &powderM_}) {
        exec_.downloadRange(*layer, offset, static_cast<size_t>(cols), row.data());
        for (int c = 0; c < cols; ++c) d[c] += row[c];
        if (layer == &unstableM_) std::copy(row.begin(), row.end(), unstable.begin() + static_cast<size_t>(r) * cols);
      }
    }
  }

  void downloadBox(SnowBox& box, bool peaks) override {
    if (peaks && avalanchePeakThicknessM_.size() == 0)
      throw std::logic_error("downloadBox: the season does not keep the avalanche's peak fields (SeasonConfig::recordFields)");
    std::pair<Buffer<float>*, Grid<float>*> fields[] = {{&compactedM_, &box.compacted}, {&stableM_, &box.stable}, {&unstableM_, &box.unstable},
                                                        {&powderM_, &box.powder}, {&avalanchePeakThicknessM_, &box.peakThickness},
                                                        {&avalanchePeakSpeedMps_, &box.peakSpeed}};
    const bool whole = box.x0 == 0 && box.y0 == 0 && box.width == spec_.width && box.height == spec_.height;
    for (int f = 0; f < (peaks ? 6 : 4); ++f) {
      Grid<float>& g = *fields[f].second;
      if (g.width() != box.width || g.height() != box.height) g.resize(box.width, box.height);
      if (whole) {
        exec_.downloadRange(*fields[f].first, 0, g.size(), g.data());
        continue;
      }
      for (int r = 0; r < box.height; ++r)
        exec_.downloadRange(*fields[f].first, static_cast<size_t>(box.y0 + r) * spec_.width + box.x0, static_cast<size_t>(box.width),
                            g.data() + static_cast<size_t>(r) * box.width);
    }
    if (!peaks) box.peakThickness = Grid<float>(), box.peakSpeed = Grid<float>();
  }

  BedformStepReport bedformStep(const BedformArgs& args) override {
    checkBedformArgs(args, spec_.width, spec_.height);
    if (!bed_.ready) makeBedformStorage(exec_, bed_, powderM_, spec_.cellCount());  // on the first bedform step only
    return runBedformStep(exec_, view(), bed_, dataIfPresent(bedformMask_), args);
  }

  bool bedformCohesion(Grid<float>& out) override {
    if (!bed_.ready) return false;
    out = Grid<float>(spec_.width, spec_.height, 0.f);
    exec_.download(bed_.cohesion, out.values());
    return true;
  }

  bool bedformDomain(std::vector<uint8_t>& out) override {
    if (!bed_.ready) return false;
    exec_.download(bed_.active, out);
    return true;
  }
  void useBedformDomain(const std::vector<uint8_t>& domain) override { exec_.upload(givenBedformDomain_, domain); }

  bool routeMapOnDevice(Grid<float>& out) override {
    if constexpr (!Exec::kDevice) {
      (void)out;
      return false;
    } else {
      out = Grid<float>(spec_.width, spec_.height, 0.f);
      out.values() = runRouteMap(exec_, view());
      return true;
    }
  }

  void uploadRouteMap(const Grid<float>& route) override {
    uploadSkierRoute(exec_, skiers_, route.values(), spec_.cellCount());
  }

  void skierBatch(const SkierArgs& args, std::vector<SkierAgent>& agents, std::vector<std::vector<double>>& paths) override {
    runSkierBatch(exec_, view(), skiers_, args, agents, paths);
  }

  void avalancheRelease(const std::vector<uint8_t>& moving, const AvalancheArgs& box) override {
    // The whole grid on the first avalanche after an upload; fields freed for a frame
    // (releaseScratch) are made again, zeroed, and released by box as before they were freed.
    const bool wholeGrid = !avalancheFieldsReady_ && !avalancheFieldsFreed_;
    if (!avalancheFieldsReady_) makeScratch(false);
    avalancheFieldsReady_ = true;
    avalancheFieldsFreed_ = false;
    if (wholeGrid) {
      exec_.upload(snowMoving_, moving);
    } else {  // outside the last avalanche's box no flag is set: the release box's rows are enough
      putAvalancheAtRest(exec_, fieldsView(), avalancheTouched_);
      for (int y = box.y0; y < box.y1; ++y) {
        const size_t at = static_cast<size_t>(y) * spec_.width + box.x0;
        exec_.uploadRange(snowMoving_, at, static_cast<size_t>(box.x1 - box.x0), moving.data() + at);
      }
    }
    runAvalancheRelease(exec_, fieldsView(), avalancheTouched_, AvalancheTouched{box.x0, box.y0, box.x1, box.y1}, wholeGrid);
  }
  std::vector<float> avalancheSteps(const AvalancheArgs& args, int substeps) override {
    return runAvalancheSteps(exec_, fieldsView(), rowStats_, avalancheTouched_, args, substeps);
  }
  void avalancheSettle(const AvalancheArgs& a) override { runAvalancheSettle(exec_, fieldsView(), a); }

  LayerTotals totals() override {
    const double area = spec_.cellAreaM2();
    const int w = spec_.width, h = spec_.height;
    LayerTotals t;
    t.compactedM3 = exec_.sum(compactedM_.data(), validCell_.data(), w, h) * area;
    t.stableM3 = exec_.sum(stableM_.data(), validCell_.data(), w, h) * area;
    t.unstableM3 = exec_.sum(unstableM_.data(), validCell_.data(), w, h) * area;
    t.powderM3 = exec_.sum(powderM_.data(), validCell_.data(), w, h) * area;
    return t;
  }

  float maxTemperatureBaseC() override {
    return exec_.maxValue(temperatureBaseC_.data(), validCell_.data(), spec_.width, spec_.height);
  }

  Exec& exec() { return exec_; }

 private:
  // The state's fields by their roles; with `taking` (the same state), the fields the season
  // downloads are moved in (HostStorage) or their host grids freed once uploaded (a device).
  void uploadState(const SnowState& s, SnowState* taking) {
    ++stateVersion_;
    spec_ = s.spec;
#define SNOW_UPLOAD_WITH_STATE(member, view, Element, role, access, fill)      \
  if constexpr (uploadedWithState(FieldRole::role)) {                          \
    if (taking && downloadedWithState(FieldRole::role)) {                      \
      exec_.uploadTaking(member##_, taking->member.values());                  \
      taking->member = Grid<Element>();                                        \
    } else {                                                                   \
      exec_.upload(member##_, s.member.values());                              \
    }                                                                          \
  }
    SNOW_STATE_FIELDS(SNOW_UPLOAD_WITH_STATE)
#undef SNOW_UPLOAD_WITH_STATE
    avalancheFieldsReady_ = avalancheFieldsFreed_ = false;
    bed_.ready = false;
    freeBuffer(givenBedformDomain_);
    makeScratch(true);
    scratchReleased_ = false;
    uploadStaticFields(s);
  }

  // The kernels' view; every kernel but the avalanche's takes it through view(), which counts the
  // call (stateVersion: a kernel that only reads is counted too, which costs a download, no more).
  SnowFieldsView view() {
    fireBeforeWrite();
    ++stateVersion_;
    return fieldsView();
  }
  SnowFieldsView fieldsView() {
    if (scratchReleased_) makeScratch(true);  // freed for a frame (releaseScratch)
    scratchReleased_ = false;
    SnowFieldsView v;
    v.width = spec_.width;
    v.height = spec_.height;
    v.cellSizeXM = static_cast<float>(spec_.cellSizeXM);
    v.cellSizeYM = static_cast<float>(spec_.cellSizeYM);
#define SNOW_VIEW_OF_FIELD(member, view, Element, role, access, fill) \
  SNOW_IF_VIEW(access, v.view = mayBeAbsent(FieldRole::role) ? dataIfPresent(member##_) : member##_.data();)
    SNOW_STATE_FIELDS(SNOW_VIEW_OF_FIELD)
#undef SNOW_VIEW_OF_FIELD
    v.bedformActive = bed_.ready ? bed_.active.data() : dataIfPresent(givenBedformDomain_);
#define SNOW_VIEW_OF_SCRATCH(view, Element, extent) v.view = view##_.data();
    SNOW_SCRATCH_FIELDS(SNOW_VIEW_OF_SCRATCH)
#undef SNOW_VIEW_OF_SCRATCH
    return v;
  }

  // Zeroed scratch fields: those made with the state (withState), or at the first avalanche.
  void makeScratch(bool withState) {
    const size_t cells = spec_.cellCount(), rows = static_cast<size_t>(spec_.height);
#define SNOW_MAKE_SCRATCH(view, Element, extent)                                                               \
  if (madeWithState(ScratchExtent::extent) == withState)                                                       \
    exec_.upload(view##_, std::vector<Element>(                                                                \
                              scratchCount(ScratchExtent::extent, cells, rows, Exec::kPowderSharesInRows)));
    SNOW_SCRATCH_FIELDS(SNOW_MAKE_SCRATCH)
#undef SNOW_MAKE_SCRATCH
  }

  template <class T>
  using Buffer = typename Exec::template Buffer<T>;
  struct NoBuffer {};  // a field the backend does not hold (host only, or in the bedforms' storage)
  template <FieldRole role, class T>
  using StateBuffer = std::conditional_t<heldByBackend(role), Buffer<T>, NoBuffer>;

  // Empty, its memory freed (an upload of nothing keeps a host vector's capacity).
  template <class T>
  void freeBuffer(Buffer<T>& b) {
    std::vector<T> none;
    exec_.uploadTaking(b, none);
  }
  template <class B>
  static auto dataIfPresent(B& b) -> decltype(b.data()) { return b.size() > 0 ? b.data() : nullptr; }
  // A buffer's storage where the host can use it in place (hostField, hostScratch): null on a device.
  template <class B>
  static void* hostData(B& b) {
    if constexpr (Exec::kDevice) {
      (void)b;
      return nullptr;
    } else {
      return static_cast<void*>(dataIfPresent(b));
    }
  }
  // A static field as it is; an art-direction one when the scene paints it (else an empty buffer).
  // A static field the host released (SeasonRun::releaseHostCopies: a day's refill replaces some of
  // them, the constant wind not) keeps the backend's values: uploaded, its buffer would be emptied
  // (on CUDA, freed).
  template <FieldRole role, class T>
  void uploadField(Buffer<T>& buffer, const Grid<T>& grid) {
    if (!optionalField(role) && grid.size() == 0 && buffer.size() == spec_.cellCount()) return;
    const bool present = !optionalField(role) || (grid.size() == spec_.cellCount() && grid.size() > 0);
    if (present) exec_.upload(buffer, grid.values());
    else exec_.upload(buffer, std::vector<T>());
  }

  Exec exec_;
  GridSpec spec_;
#define SNOW_STATE_BUFFER(member, view, Element, role, access, fill) StateBuffer<FieldRole::role, Element> member##_;
  SNOW_STATE_FIELDS(SNOW_STATE_BUFFER)
#undef SNOW_STATE_BUFFER
#define SNOW_SCRATCH_BUFFER(view, Element, extent) Buffer<Element> view##_;
  SNOW_SCRATCH_FIELDS(SNOW_SCRATCH_BUFFER)
#undef SNOW_SCRATCH_BUFFER
  Buffer<float> editWeight_;
  bool avalancheFieldsReady_ = false;
  bool scratchReleased_ = false;
  bool avalancheFieldsFreed_ = false;  // by releaseScratch since the last release (not by an upload)
  uint64_t stateVersion_ = 0;
  AvalancheTouched avalancheTouched_;  // phenomena/avalanches.h
  BedformStorage<Exec> bed_;
  Buffer<uint8_t> givenBedformDomain_;  // useBedformDomain's, read while bed_ is not ready
  SkierStorage<Exec> skiers_;
};

}  // namespace snow
