// Builds a pendulum with the installed headers and library, swings it for a second and checks
// that it swung through the bottom (the installed package works end to end).
#include <cmath>
#include <cstdio>

#include "engine/model/builder.h"
#include "engine/solver/solver_featherstone.h"

int main() {
  using namespace novaphy;
  ModelBuilder builder;
  const int link = builder.add_body(RigidBody::from_box(1, Vec3(0.05, 0.5, 0.05)));
  JointOptions options;
  options.dof.axis = Vec3::UnitZ();
  options.child_xform.p = Vec3(-0.5, 0, 0);  // horizontal at q = 0
  builder.add_joint_revolute(-1, link, options);
  const Model model = builder.finalize();
  CollisionPipeline pipeline(model);
  Contacts contacts = pipeline.contacts();
  SolverFeatherstone solver(model);
  State state = model.state();
  const Control control = model.control();
  double lowest = 0;
  for (int k = 0; k < 120; ++k) {
    pipeline.collide(state, contacts);
    solver.step(state, state, control, contacts, 1.0 / 120);
    lowest = std::min(lowest, state.joint_q[0]);
  }
  std::printf("consumer: the pendulum swung to %.3f rad\n", lowest);
  return lowest < -1.0 ? 0 : 1;
}
