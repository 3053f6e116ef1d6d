#include "engine/solver/simulate.h"

#include <gtest/gtest.h>

#include "engine/import/mjcf_import.h"
#include "engine/model/error.h"
#include "solver_test_support.h"

namespace novaphy {
namespace {

using solver_test::Scene;

// three quadrupeds falling onto the floor, each scene with its own pipeline, contacts and solver
ModelBuilder quadrupeds() {
  ModelBuilder robot, worlds;
  import_mjcf(robot, NOVAPHY_SCENE_DIR "/quadruped.xml");
  worlds.replicate(robot, 3);
  return worlds;
}

TEST(Simulate, SubstepsAreTheLoopWrittenOutBitForBit) {
  const ModelBuilder builder = quadrupeds();
  Scene looped(builder), simulated(builder), at_timestep(builder);
  const Scalar dt = looped.model.timestep;
  EXPECT_EQ(dt, 0.005);  // (the file's <option timestep>)
  for (int action = 0; action < 20; ++action) {
    for (Scene* scene : {&looped, &simulated, &at_timestep})
      for (size_t k = 0; k < scene->control.joint_f.size(); ++k) scene->control.joint_f[k] = 0.1 * action - 0.05 * k;
    looped.run(4 * dt, dt);
    simulate(simulated.pipeline, simulated.solver, simulated.state, simulated.control, simulated.contacts, 4, dt);
    simulate(at_timestep.pipeline, at_timestep.solver, at_timestep.state, at_timestep.control, at_timestep.contacts, 4);
  }
  EXPECT_GT(looped.contacts.contact_count, 0);  // (on the floor: the contacts' warm starts carry between calls)
  for (const Scene* scene : {&simulated, &at_timestep}) {
    EXPECT_EQ(scene->state.joint_q, looped.state.joint_q);
    EXPECT_EQ(scene->state.joint_qd, looped.state.joint_qd);
    EXPECT_EQ(scene->state.body_q, looped.state.body_q);
  }
}

TEST(Simulate, BadSubstepsOrDtAreNamedBeforeAnythingIsStepped) {
  Scene scene(quadrupeds());
  const State before = scene.state;
  auto call = [&](int substeps, Scalar dt) {
    simulate(scene.pipeline, scene.solver, scene.state, scene.control, scene.contacts, substeps, dt);
  };
  EXPECT_THROW(
      {
        try {
          call(0, 0.002);
        } catch (const Error& e) {
          EXPECT_STREQ(e.what(), "simulate: substeps must be >= 1, got 0");
          throw;
        }
      },
      Error);
  for (const Scalar dt : {-0.001, std::nan(""), HUGE_VAL}) EXPECT_THROW(call(2, dt), Error) << dt;
  EXPECT_EQ(scene.state.joint_q, before.joint_q);
}

}  // namespace
}  // namespace novaphy
