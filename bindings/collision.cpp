// CollisionPipeline and Contacts: contact arrays are numpy views over the first contact_count entries; a view keeps
// its Contacts alive, and with it the arrays a growth replaced (Contacts::retired), so an old view never dangles.
#include "bindings/bindings.h"
#include "engine/collision/pipeline.h"

namespace novaphy::python {

void bind_collision(py::module_& m) {
  py::enum_<ContactOverflow>(m, "ContactOverflow",
                             "What collide does when it finds more contacts than the buffer holds.")
      .value("Grow", ContactOverflow::Grow, "the buffer grows to hold them all (fetch its views again)")
      .value("Raise", ContactOverflow::Raise, "collide raises naming the capacity needed; nothing is written")
      .value("Drop", ContactOverflow::Drop, "those beyond the capacity are dropped, the last worlds' first");
  auto contacts = py::class_<Contacts>(
      m, "Contacts",
      "Contacts of the last collide(), numpy views of contact_count rows. A view shows the buffer as it was when "
      "fetched: fetch it again after each collide (a collide that grows the buffer moves its arrays; an older view "
      "stays valid but reads the old ones).");
  contacts.def_readonly("contact_count", &Contacts::contact_count)
      .def_readonly("contact_capacity", &Contacts::contact_capacity)
      .def_readonly("contact_dropped", &Contacts::contact_dropped,
                    "Contacts the last collide found beyond the capacity and dropped (on_overflow Drop).");
#define NOVAPHY_BIND_CONTACT_FIELD(T, name, count, width)            \
  contacts.def_property_readonly(#name, [](py::object self) {        \
    Contacts& c = self.cast<Contacts&>();                            \
    return view(c.name.data(), c.contact_count, width, self, false); \
  });
  NOVAPHY_CONTACT_FIELDS(NOVAPHY_BIND_CONTACT_FIELD)
#undef NOVAPHY_BIND_CONTACT_FIELD

  py::class_<CollisionPipeline>(m, "CollisionPipeline", "Broad and narrow phase for planes, spheres, boxes, capsules.")
      .def(py::init([](const Model& model, int contact_capacity, ContactOverflow on_overflow, Scalar margin,
                       bool self_collision, int num_threads, bool count_serial_time) {
             CollisionOptions options;
             options.contact_capacity = contact_capacity;
             options.on_overflow = on_overflow;
             options.margin = margin;
             options.self_collision = self_collision;
             options.num_threads = num_threads;
             options.count_serial_time = count_serial_time;
             return new CollisionPipeline(model, options);
           }),
           py::arg("model"), py::kw_only(), py::arg("contact_capacity") = 0,
           py::arg("on_overflow") = ContactOverflow::Grow, py::arg("margin") = 0.01, py::arg("self_collision") = true,
           py::arg("num_threads") = 0, py::arg("count_serial_time") = false, py::keep_alive<1, 2>())
      .def("contacts", &CollisionPipeline::contacts, "A contacts buffer sized for this pipeline.")
      .def(
          "collide",
          [](CollisionPipeline& self, State& state, Contacts& contacts) {
            const ExclusiveCall held = self.hold();  // (before the conversion: a refused call writes nothing)
            const Widened<State> read(state, false, self.options().num_threads);
            self.collide(state, contacts);
          },
          py::arg("state"), py::arg("contacts"), py::call_guard<py::gil_scoped_release>(),
          "Contacts between the shapes at state.body_q; one collide at a time per pipeline (another thread's "
          "raises).")
      .def_property_readonly(
          "serial_seconds", [](const CollisionPipeline& self) { return serial_seconds_dict(self.serial_seconds()); },
          "Seconds of whole collides and of their parallel work when made with count_serial_time, the collides "
          "timed, and the serial share (the rest over the whole).")
      .def("reset_serial_seconds", &CollisionPipeline::reset_serial_seconds, "Zeroes serial_seconds.");
}

}  // namespace novaphy::python
