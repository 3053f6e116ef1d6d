// CollisionPipeline and Contacts: contact arrays are numpy views over the first contact_count entries.
#include "engine/collision.h"

#include "bindings/bindings.h"

namespace novaphy::python {

void bind_collision(py::module_& m) {
  auto contacts =
      py::class_<Contacts>(m, "Contacts", "Contacts of the last collide(), numpy views of contact_count rows.");
  contacts.def_readonly("contact_count", &Contacts::contact_count)
      .def_readonly("contact_capacity", &Contacts::contact_capacity)
      .def_readonly("contact_dropped", &Contacts::contact_dropped, "Contacts found beyond the capacity last time.");
#define NOVAPHY_BIND_CONTACT_FIELD(T, name, count, width)            \
  contacts.def_property_readonly(#name, [](py::object self) {        \
    Contacts& c = self.cast<Contacts&>();                            \
    return view(c.name.data(), c.contact_count, width, self, false); \
  });
  NOVAPHY_CONTACT_FIELDS(NOVAPHY_BIND_CONTACT_FIELD)
#undef NOVAPHY_BIND_CONTACT_FIELD

  py::class_<CollisionPipeline>(m, "CollisionPipeline", "Broad and narrow phase for planes, spheres, boxes, capsules.")
      .def(py::init([](const Model& model, int contact_capacity, Scalar margin, bool self_collision, int num_threads,
                       bool count_serial_time) {
             CollisionOptions options;
             options.contact_capacity = contact_capacity;
             options.margin = margin;
             options.self_collision = self_collision;
             options.num_threads = num_threads;
             options.count_serial_time = count_serial_time;
             return new CollisionPipeline(model, options);
           }),
           py::arg("model"), py::kw_only(), py::arg("contact_capacity") = 0, py::arg("margin") = 0.01,
           py::arg("self_collision") = true, py::arg("num_threads") = 0, py::arg("count_serial_time") = false,
           py::keep_alive<1, 2>())
      .def("contacts", &CollisionPipeline::contacts, "A contacts buffer sized for this pipeline.")
      .def("collide", &CollisionPipeline::collide, py::arg("state"), py::arg("contacts"),
           py::call_guard<py::gil_scoped_release>(), "Contacts between the shapes at state.body_q.")
      .def_property_readonly(
          "serial_seconds", [](const CollisionPipeline& self) { return serial_seconds_dict(self.serial_seconds()); },
          "Seconds of whole collides and of their parallel work when made with count_serial_time, the collides "
          "timed, and the serial share (the rest over the whole).")
      .def("reset_serial_seconds", &CollisionPipeline::reset_serial_seconds, "Zeroes serial_seconds.");
}

}  // namespace novaphy::python
