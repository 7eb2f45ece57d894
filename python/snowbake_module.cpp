// The Python module `snowbake` (docs/python.md): bake, plan, info, SceneError. The bake runs with the
// GIL released; the progress callable is called with the GIL held, from the bake's threads.
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <OpenImageIO/imageio.h>

#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>

#include "bake/bake.h"
#include "bake/plan.h"
#include "bake/progress.h"
#include "core/errors.h"
#include "core/stop_request.h"
#include "tools/info.h"

namespace py = pybind11;
namespace fs = std::filesystem;
using namespace snow;

namespace {

// Progress as Python calls: progress({"type": ..., "stage": ..., ...}), one dict a JSON line.
class PythonProgress : public ProgressSink {
 public:
  explicit PythonProgress(py::object callback) : callback_(std::move(callback)) {}
  ~PythonProgress() override {
    py::gil_scoped_acquire gil;
    callback_ = py::object();
  }
  void stage(const std::string& name, double fraction) override {
    py::gil_scoped_acquire gil;  // before any Python object is made
    callLocked(py::dict(py::arg("type") = "progress", py::arg("stage") = name, py::arg("fraction") = fraction));
  }
  void event(const std::string& stage, const std::string& name, const ProgressFields& fields) override {
    py::gil_scoped_acquire gil;
    py::dict d(py::arg("type") = "event", py::arg("stage") = stage, py::arg("event") = name);
    py::module_ json = py::module_::import("json");
    for (const auto& [key, value] : fields) d[py::str(key)] = json.attr("loads")(value);
    callLocked(d);
  }
  void finish(const ProgressOutcome&) override {}
  void rethrow() {
    if (error_) std::rethrow_exception(error_);
  }

 private:
  void callLocked(const py::dict& d) {
    if (error_) return;  // the first error raised by the callable ends its calls
    try {
      callback_(d);
    } catch (...) {
      error_ = std::current_exception();
    }
  }
  py::object callback_;
  std::exception_ptr error_;
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// A Python value as --set writes it: strings quoted, booleans lower case, lists as TOML arrays.
std::string tomlValue(const py::handle& v) {
  if (py::isinstance<py::bool_>(v)) return v.cast<bool>() ? "true" : "false";
  if (py::isinstance<py::int_>(v) || py::isinstance<py::float_>(v)) return py::str(py::module_::import("builtins").attr("repr")(v));
  if (py::isinstance<py::str>(v)) return py::module_::import("json").attr("dumps")(v).cast<std::string>();
  if (py::isinstance<py::list>(v) || py::isinstance<py::tuple>(v)) {
    std::string s = "[";
    for (const py::handle& item : v) s += (s.size() > 1 ? "," : "") + tomlValue(item);
    return s + "]";
  }
  throw py::type_error("overrides: a value must be a bool, number, string or list");
}

// One float32 channel of an EXR the bake wrote.
py::array_t<float> readExr(const std::string& path) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) throw std::runtime_error(path + ": cannot open: " + OIIO::geterror());
  const OIIO::ImageSpec& spec = in->spec();
  py::array_t<float> a({spec.height, spec.width});
  if (!in->read_image(0, 0, 0, 1, OIIO::TypeDesc::FLOAT, a.mutable_data())) throw std::runtime_error(path + ": " + in->geterror());
  return a;
}

struct Result {
  std::string out;
  std::vector<std::string> files;
  py::object manifest;
  // The layer's EXR at the season's end, or at a frame day.
  py::array_t<float> layer(const std::string& name, std::optional<int> day) const {
    char frame[16];
    if (day) std::snprintf(frame, sizeof frame, ".%04d", *day);
    const fs::path path = day ? fs::path(out) / "frames" / (name + frame + ".exr") : fs::path(out) / (name + ".exr");
    if (!fs::exists(path)) throw py::key_error(path.string() + ": not written by this bake (outputs.layers, outputs.frames_days)");
    return readExr(path.string());
  }
};

BakeOptions bakeOptions(const std::string& scene, const std::string& out, const py::dict& overrides, std::optional<int> threads) {
  BakeOptions o;
  o.scene = scene;
  o.outDir = out;
  o.threads = threads;
  o.progress = false;
  for (const auto& [key, value] : overrides) o.sets.push_back(py::str(key).cast<std::string>() + "=" + tomlValue(value));
  return o;
}

Result bake(const std::string& scene, const std::string& out, const py::dict& overrides, std::optional<int> threads,
            const py::object& progress) {
  BakeOptions o = bakeOptions(scene, out, overrides, threads);
  std::optional<PythonProgress> sink;
  if (!progress.is_none()) o.progressSink = &sink.emplace(progress);
  std::ostringstream log;
  BakeResult r;
  {
    const StopOnSignals stopOnSignals;  // Ctrl-C: the bake stops between steps, then KeyboardInterrupt
    py::gil_scoped_release released;
    r = runBake(o, log);
  }
  if (sink) sink->rethrow();
  Result result{out, r.files, py::module_::import("json").attr("loads")(slurp(r.files.back()))};
  return result;
}

// `snowbake plan --json` as a dict: what bake(...) with the same arguments would write.
py::object plan(const std::string& scene, const std::string& out, const py::dict& overrides, std::optional<int> threads) {
  const BakeOptions o = bakeOptions(scene, out, overrides, threads);
  std::string json;
  {
    py::gil_scoped_release released;
    json = planToJson(planBake(o));
  }
  return py::module_::import("json").attr("loads")(json);
}

}  // namespace

PYBIND11_MODULE(snowbake, m) {
  m.doc() = "snowbake: bake a season of snow from Python (docs/python.md)";
  m.attr("__version__") = programVersion();
  static py::exception<InputError> sceneError(m, "SceneError", PyExc_ValueError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      sceneError(e.what());
    } catch (const Interrupted& e) {
      PyErr_SetString(PyExc_KeyboardInterrupt, e.what());
    }
  });
  py::class_<Result>(m, "Result")
      .def_readonly("files", &Result::files)
      .def_readonly("manifest", &Result::manifest)
      .def_readonly("out", &Result::out)
      .def("layer", &Result::layer, py::arg("name"), py::arg("day") = py::none());
  m.def("bake", &bake, py::arg("scene"), py::kw_only(), py::arg("out") = "snowbake-out", py::arg("overrides") = py::dict(),
        py::arg("threads") = py::none(), py::arg("progress") = py::none(),
        "Bake SCENE (a path or preset:default) into OUT; overrides are --set KEY=VALUE. Raises SceneError on bad input.");
  m.def("plan", &plan, py::arg("scene"), py::kw_only(), py::arg("out") = "snowbake-out", py::arg("overrides") = py::dict(),
        py::arg("threads") = py::none(),
        "What bake(...) with the same arguments would do, as `snowbake plan --json`: files, stages, peak memory, time class. Writes nothing.");
  m.def("info", [](const std::string& path) { return py::module_::import("json").attr("loads")(describeTerrain(path, true)); },
        py::arg("path"), "What snowbake understands of a terrain file or scene, as `snowbake info --json`.");
}
