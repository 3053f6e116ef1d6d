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
      .def(py::init([](const Model& model, int contact_capacity, Scalar margin, bool self_collision, int num_threads) {
             CollisionOptions options;
             options.contact_capacity = contact_capacity;
             options.margin = margin;
             options.self_collision = self_collision;
             options.num_threads = num_threads;
             return new CollisionPipeline(model, options);
           }),
           py::arg("model"), py::kw_only(), py::arg("contact_capacity") = 0, py::arg("margin") = 0.01,
           py::arg("self_collision") = true, py::arg("num_threads") = 0, py::keep_alive<1, 2>())
      .def("contacts", &CollisionPipeline::contacts, "A contacts buffer sized for this pipeline.")
      .def("collide", &CollisionPipeline::collide, py::arg("state"), py::arg("contacts"),
           py::call_guard<py::gil_scoped_release>(), "Contacts between the shapes at state.body_q.");
}

}  // namespace novaphy::python
