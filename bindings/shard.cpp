// Worlds split into shards (engine/mpi/shard.h): the pieces novaphy.mpi builds its sharded batch from.
#include "engine/mpi/shard.h"

#include <pybind11/functional.h>

#include "bindings/bindings.h"

namespace novaphy::python {

void bind_shard(py::module_& m) {
  py::class_<WorldRange>(m, "WorldRange", "A contiguous range [begin, end) of global worlds.")
      .def_readonly("begin", &WorldRange::begin)
      .def_readonly("end", &WorldRange::end)
      .def_property_readonly("count", &WorldRange::count)
      .def("__repr__", [](const WorldRange& r) {
        return "WorldRange(" + std::to_string(r.begin) + ", " + std::to_string(r.end) + ")";
      });

  py::class_<WorldLayout>(m, "WorldLayout", "Entries per world of a model whose worlds share one layout.")
      .def_readonly("world_count", &WorldLayout::world_count)
      .def_readonly("body_count", &WorldLayout::body_count)
      .def_readonly("joint_coord_count", &WorldLayout::joint_coord_count)
      .def_readonly("joint_dof_count", &WorldLayout::joint_dof_count)
      .def_readonly("articulation_count", &WorldLayout::articulation_count)
      .def_readonly("actuator_count", &WorldLayout::actuator_count);

  m.def("shard_range", &shard_range, py::arg("world_count"), py::arg("rank"), py::arg("size"),
        "The worlds rank `rank` of `size` owns: contiguous, in rank order, the first world_count % size ranks one "
        "more.");
  m.def(
      "build_worlds",
      [](const ModelBuilder& shared, const py::function& build_world, WorldRange range) {
        // each world is built into a builder Python owns (the callback may keep it), then copied into the scene
        return build_worlds(
            shared,
            [&](ModelBuilder& builder, int world) {
              py::object built = py::cast(ModelBuilder());
              build_world(built, world);
              builder = built.cast<const ModelBuilder&>();
            },
            range);
      },
      py::arg("shared"), py::arg("build_world"), py::arg("range"),
      "Model of `shared` (static shapes only, e.g. the ground) followed by one world per index in `range`, built "
      "by build_world(builder, world) into a new builder of its own. The scene takes the worlds' gravity and "
      "timestep where `shared` was made without them.");
  m.def("world_layout", &world_layout, py::arg("model"),
        "Entries per world; raises ValueError naming the first entity whose count or order differs between "
        "worlds.");
}

}  // namespace novaphy::python
