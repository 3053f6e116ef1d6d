// Shared declarations of the pybind11 module: one bind_* per engine file.
#pragma once

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <limits>
#include <sstream>
#include <string>
#include <type_traits>

#include "engine/collision/pipeline.h"
#include "engine/model/model.h"
#include "engine/threads/exclusive_call.h"
#include "engine/threads/parallel.h"

namespace novaphy::python {

namespace py = pybind11;

void bind_model(py::module_& m);
void bind_builder(py::module_& m);
void bind_eval(py::module_& m);
void bind_collision(py::module_& m);
void bind_solver_featherstone(py::module_& m);
void bind_solver_maximal(py::module_& m);  // after bind_solver_featherstone (DivergencePolicy, JointSupportMatrix)
void bind_shard(py::module_& m);
void bind_mujoco(py::module_& m);  // after bind_builder: adds ModelBuilder.add_mujoco_model

// a setting's accepted range as the docs write it ("" for a bool or an enum)
template <typename T, typename Low, typename High>
std::string setting_range(Low lowest, High highest) {
  if constexpr (std::is_same_v<T, bool> || std::is_enum_v<T>) {
    return "";
  } else {
    std::ostringstream os;
    os.precision(17);
    const bool unbounded =
        static_cast<T>(highest) == std::numeric_limits<T>::max() ||
        (std::numeric_limits<T>::has_infinity && static_cast<T>(highest) == std::numeric_limits<T>::infinity());
    if (unbounded)
      os << ">= " << lowest;
    else
      os << "[" << lowest << ", " << highest << "]";
    return os.str();
  }
}

// the settings struct Type (read-write, one property a setting) of field table TABLE (engine/solver/settings.h) as
// the Python class of that name, with its static fields(): per setting its name, C++ type, default, accepted range,
// unit and doc
#define NOVAPHY_BIND_SETTINGS_CLASS(module, Type, TABLE, doc)                                          \
  do {                                                                                                 \
    using Settings = Type;                                                                             \
    py::class_<Settings> settings_class(module, #Type, doc);                                           \
    settings_class.def(py::init<>());                                                                  \
    TABLE(NOVAPHY_BIND_SETTING)                                                                        \
    settings_class.def_static(                                                                         \
        "fields",                                                                                      \
        [] {                                                                                           \
          py::list fields;                                                                             \
          TABLE(NOVAPHY_DESCRIBE_SETTING)                                                              \
          return fields;                                                                               \
        },                                                                                             \
        "The settings table: per setting its name, C++ type, default, accepted range, unit and doc."); \
  } while (0)
// (one line of a table, in NOVAPHY_BIND_SETTINGS_CLASS)
#define NOVAPHY_BIND_SETTING(type, name, value, lowest, highest, unit, doc) \
  settings_class.def_readwrite(#name, &Settings::name, doc);
#define NOVAPHY_DESCRIBE_SETTING(type, name, value, lowest, highest, unit, doc)                                  \
  fields.append(py::dict(py::arg("name") = #name, py::arg("type") = #type, py::arg("default") = Settings{}.name, \
                         py::arg("range") = setting_range<type>(lowest, highest), py::arg("unit") = unit,        \
                         py::arg("doc") = doc));

// a numpy view of `count` rows of `width` values owned by `owner` (no copy); width 1 gives a 1-D array
template <typename T>
py::array view(T* data, int count, int width, py::handle owner, bool writeable) {
  std::vector<py::ssize_t> shape{count}, strides{static_cast<py::ssize_t>(width * sizeof(T))};
  if (width > 1) shape.push_back(width), strides.push_back(sizeof(T));
  py::array array(py::dtype::of<T>(), shape, strides, data, owner);
  if (!writeable) array.attr("setflags")(py::arg("write") = false);
  return array;
}

// a call on a State or Control of a float32 model, whose float32 arrays are what Python holds while the engine
// reads and writes its double fields: they are widened from the arrays before the call, and a State or Control
// the call writes is rounded back into them after it. Nothing for a float64 model's. (Made without the GIL.)
template <typename Owner>
class Widened {
 public:
  // (on `threads` threads, 0: OpenMP's default)
  Widened(Owner& owner, bool written, int threads = 0) : owner_(owner), written_(written), threads_(threads) {
    owner_.from_float32(threads_);
  }
  Widened(const Widened&) = delete;
  Widened& operator=(const Widened&) = delete;
  ~Widened() {
    if (written_) owner_.to_float32(threads_);
  }

 private:
  Owner& owner_;
  bool written_;
  int threads_;
};

// serial_seconds as a dict: step, parallel, steps and share
inline py::dict serial_seconds_dict(const SerialSeconds& t) {
  py::dict d;
  d["step"] = t.step;
  d["parallel"] = t.parallel;
  d["steps"] = t.steps;
  d["share"] = t.share();
  return d;
}

// a solver's step(state_in, state_out, control, contacts, dt): the solver's one-call flag held before a float32
// state or control is widened (a refused call writes nothing), the GIL released
template <typename Solver, typename Class>
void def_step(Class& c, const char* doc) {
  c.def(
      "step",
      [](Solver& self, State& in, State& out, Control& control, Contacts& contacts, Scalar dt) {
        const int threads = self.settings.num_threads;
        const ExclusiveCall held = self.hold();
        const Widened<State> written(out, true, threads);
        if (&in != &out) in.from_float32(threads);
        const Widened<Control> read(control, false, threads);
        self.step(in, out, control, contacts, dt);
      },
      py::arg("state_in"), py::arg("state_out"), py::arg("control"), py::arg("contacts"), py::arg("dt"),
      py::call_guard<py::gil_scoped_release>(), doc);
}

}  // namespace novaphy::python
