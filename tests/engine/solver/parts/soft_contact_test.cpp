// MuJoCo's soft contacts (engine/solver/parts/contact_softness.h contact_softness): the weights they scale by, and
// where bodies come to rest on them, against MuJoCo 2.2.2 on the same MJCF.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "engine/import/mjcf_import.h"
#include "engine/model/builder.h"
#include "engine/solver/parts/rows.h"
#include "solver_test_support.h"
#include "test_support.h"
#include "test_support_errors.h"

namespace novaphy {
namespace {

using MjModelPtr = std::unique_ptr<mjModel, void (*)(mjModel*)>;
using MjDataPtr = std::unique_ptr<mjData, void (*)(mjData*)>;

// body_invweight0, worked out by NovaPhy from joint_q0 (CRBA and its Jacobians), is MuJoCo's own
TEST(SoftContacts, BodyWeightsAreMujocos) {
  for (const std::string& path : {std::string(NOVAPHY_SCENE_DIR "/quadruped.xml"),
                                  std::string("/usr/share/mujoco/model/humanoid/humanoid.xml")}) {
    ModelBuilder builder;
    const MujocoImport import = import_mjcf(builder, path);
    const Model model = builder.finalize();
    const MjModelPtr m(load_mujoco_model(path), mj_deleteModel);
    int compared = 0;
    for (int b = 1; b < m->nbody; ++b) {
      const int body = import.body_map[b];
      if (body < 0) continue;
      for (int k = 0; k < 2; ++k)
        EXPECT_NEAR(model.body_invweight0[2 * body + k], m->body_invweight0[2 * b + k],
                    1e-9 * m->body_invweight0[2 * b + k])
            << path << " body " << b << (k == 0 ? " translation" : " rotation");
      ++compared;
    }
    EXPECT_GT(compared, 4) << path;
  }
}

// a free body's weights are 1/m and the mean of its inverse principal inertias; a body welded to the world has
// none (an articulation of no dofs: a fuzzer's find)
TEST(SoftContacts, FreeBodiesWeighTheirInverseInertiaWeldedOnesNothing) {
  ModelBuilder builder;
  const int free = builder.add_body(RigidBody::from_box(2, Vec3(0.1, 0.2, 0.3)));
  const int welded = builder.add_body(RigidBody::from_sphere(1, 0.1));
  builder.add_joint_fixed(-1, welded);
  const Model model = builder.finalize();
  const Mat3 I = Eigen::Map<const Eigen::Matrix<Scalar, 3, 3, Eigen::RowMajor>>(&model.body_inertia[9 * free]);
  EXPECT_NEAR(model.body_invweight0[2 * free], 0.5, 1e-12);
  EXPECT_NEAR(model.body_invweight0[2 * free + 1], I.inverse().trace() / 3, 1e-9);
  EXPECT_EQ(model.body_invweight0[2 * welded], 0);
  EXPECT_EQ(model.body_invweight0[2 * welded + 1], 0);
}

// MuJoCo's impedance: dmin at the surface, dmax from `width` in, the midpoint and power shaping between
TEST(SoftContacts, ImpedanceFollowsSolimp) {
  const Scalar solimp[5] = {0.2, 0.9, 0.01, 0.4, 3};
  EXPECT_NEAR(impedance(solimp, 0), 0.2, 1e-15);
  EXPECT_NEAR(impedance(solimp, -0.02), 0.9, 1e-15);
  const Scalar u = 0.3;  // below the midpoint: y = u^p / mid^(p-1)
  EXPECT_NEAR(impedance(solimp, -u * 0.01), 0.2 + 0.7 * std::pow(u, 3) / std::pow(0.4, 2), 1e-15);
  const Scalar w = 0.7;  // above: y = 1 - (1-u)^p / (1-mid)^(p-1)
  EXPECT_NEAR(impedance(solimp, -w * 0.01), 0.2 + 0.7 * (1 - std::pow(0.3, 3) / std::pow(0.6, 2)), 1e-15);
  const Scalar flat[5] = {0.95, 0.95, 0.001, 0.5, 2};
  EXPECT_EQ(impedance(flat, -0.0005), 0.95);
  // outside MuJoCo's ranges, clamped as MuJoCo clamps: dmin and dmax into [1e-4, 0.9999] (here both 0.9999, flat),
  // the midpoint likewise, the power to >= 1 (linear), the width to >= 0 (flat)
  const Scalar above[5] = {2, 1, 0.01, 0.5, 2};
  EXPECT_EQ(impedance(above, -0.005), 0.9999);
  const Scalar linear[5] = {0.2, 0.9, 0.01, 1.5, 0.5};
  EXPECT_NEAR(impedance(linear, -0.003), 0.2 + 0.7 * 0.3, 1e-15);
  const Scalar no_width[5] = {0.2, 0.9, -0.01, 0.5, 2};
  EXPECT_NEAR(impedance(no_width, -0.003), 0.55, 1e-15);
  // a power so high that mid^(p-1) underflows: a step from dmin to dmax at the midpoint, never 0 / 0
  const Scalar steep[5] = {0.2, 0.9, 0.01, 0.5, 1e300};
  EXPECT_EQ(impedance(steep, -0.003), 0.2);
  EXPECT_DOUBLE_EQ(impedance(steep, -0.007), 0.9);
}

// the bodies' heights after 2 s from the MJCF at `path`, NovaPhy's; each within 0.2 mm of MuJoCo's
std::vector<Scalar> rest_heights_as_in_mujoco(const std::string& path, const std::vector<std::string>& bodies) {
  const MjModelPtr m(load_mujoco_model(path), mj_deleteModel);
  const MjDataPtr d(mj_makeData(m.get()), mj_deleteData);
  for (int k = 0; k < 1000; ++k) mj_step(m.get(), d.get());
  ModelBuilder builder;
  const MujocoImport import = import_mjcf(builder, path);
  solver_test::Scene scene(builder);
  scene.run(2, 0.002);
  std::vector<Scalar> heights;
  for (const std::string& name : bodies) {
    const int b = mj_name2id(m.get(), mjOBJ_BODY, name.c_str());
    const Scalar mujoco = d->xpos[3 * b + 2], novaphy = scene.position(import.body_map[b]).z();
    EXPECT_NEAR(novaphy, mujoco, 2e-4) << name;
    heights.push_back(novaphy);
  }
  return heights;
}

// bodies dropped on soft contacts come to rest as deep as in MuJoCo: MuJoCo's defaults on a box; a sphere
// of Go1's feet's solimp (soft at the surface, hard 23 mm in), which sinks over a centimetre; a capsule of a
// slower solref; a cylinder on a priority-deciding floor
TEST(SoftContacts, BodiesRestAtMujocosDepth) {
  const std::string path = test::write_temp_file("soft_rest.xml", R"(
<mujoco>
  <option timestep="0.002"/>
  <worldbody>
    <geom name="floor" type="plane" size="5 5 0.1"/>
    <body name="box" pos="0 0 0.12"><freejoint/><geom type="box" size="0.1 0.1 0.1" mass="2"/></body>
    <body name="foot" pos="1 0 0.03"><freejoint/>
      <geom type="sphere" size="0.023" mass="3" priority="1" solimp="0.015 1 0.023"/></body>
    <body name="capsule" pos="2 0 0.06" euler="0 90 0"><freejoint/>
      <geom type="capsule" size="0.05 0.2" mass="1" solref="0.05 0.5"/></body>
    <body name="can" pos="3 0 0.12"><freejoint/><geom type="cylinder" size="0.1 0.1" mass="4" solmix="3"/></body>
  </worldbody>
</mujoco>)");
  const std::vector<Scalar> heights = rest_heights_as_in_mujoco(path, {"box", "foot", "capsule", "can"});
  EXPECT_LT(heights[1], 0.023 - 0.005);  // (the foot sinks more than a rigid contact's slop would allow)
  std::filesystem::remove(path);
}

// spheres each of its own solref, solimp, priority and solmix (more distinct materials than the step tables: each
// contact's pair made as it is read, engine/solver/parts/contact_material.h ShapeContacts) rest as deep as in MuJoCo
TEST(SoftContacts, ManyMaterialsRestAtMujocosDepth) {
  constexpr int kSpheres = 40;
  static_assert(kSpheres + 1 > ShapeContacts::kPairTableMaterials);
  std::string xml = R"(<mujoco><option timestep="0.002"/><worldbody>
    <geom name="floor" type="plane" size="20 20 0.1" solmix="2"/>)";
  for (int k = 0; k < kSpheres; ++k)
    xml += "<body name=\"s" + std::to_string(k) + "\" pos=\"" + std::to_string(0.3 * k) +
           " 0 0.05\"><freejoint/><geom type=\"sphere\" size=\"0.05\" mass=\"" + std::to_string(1 + 0.05 * k) +
           "\" solref=\"" + std::to_string(0.01 + 0.001 * k) + " " + std::to_string(0.5 + 0.02 * k) + "\" solimp=\"" +
           std::to_string(0.5 + 0.01 * k) + " 0.99 " + std::to_string(0.005 + 0.0005 * k) + "\" priority=\"" +
           std::to_string(k % 3 == 0 ? 1 : 0) + "\" solmix=\"" + std::to_string(0.5 + 0.1 * k) + "\"/></body>";
  xml += "</worldbody></mujoco>";
  const std::string path = test::write_temp_file("soft_many.xml", xml);
  std::vector<std::string> spheres;
  for (int k = 0; k < kSpheres; ++k) spheres.push_back("s" + std::to_string(k));
  const std::vector<Scalar> heights = rest_heights_as_in_mujoco(path, spheres);
  for (int k = 0; k < kSpheres; ++k) EXPECT_LT(heights[k], 0.05 - 1e-4) << spheres[k];  // (soft: each sank)
  std::filesystem::remove(path);
}

// a contact's softness follows the step's dt where a solref's time constant is under two steps (MuJoCo's refsafe):
// a solver that stepped at another dt steps a state as a new one does
TEST(SoftContacts, SoftnessFollowsTheStepsDt) {
  ModelBuilder builder;
  const int ball = builder.add_body(RigidBody::from_sphere(1, 0.05), Transform{Vec3(0, 0.049, 0)});
  builder.add_joint_free(-1, ball);
  ShapeOptions soft;
  soft.solref = {0.005, 1};
  builder.add_shape_sphere(ball, 0.05, soft);
  builder.add_ground_plane(0, soft);
  solver_test::Scene used(builder), fresh(builder);
  used.run(0.04, 0.004);
  const State start = used.state;
  for (solver_test::Scene* scene : {&used, &fresh}) {
    scene->state = start;
    scene->run(0.01, 0.001);
  }
  EXPECT_EQ(used.state.joint_q, fresh.state.joint_q);
  EXPECT_EQ(used.state.joint_qd, fresh.state.joint_qd);
}

// a ball spinning on the spot (condim 4), one rolling with condim 6 and one with condim 3
constexpr const char* kSpinAndRoll = R"(
<mujoco>
  <option timestep="0.002" cone="elliptic"/>
  <worldbody>
    <geom name="floor" type="plane" size="10 10 0.1"/>
    <body name="spin" pos="0 0 0.1"><freejoint/>
      <geom type="sphere" size="0.1" mass="1" condim="4" friction="1 0.005 0.0001"/></body>
    <body name="roll6" pos="0 1 0.1"><freejoint/>
      <geom type="sphere" size="0.1" mass="1" condim="6" friction="1 0.005 0.002"/></body>
    <body name="roll3" pos="0 2 0.1"><freejoint/>
      <geom type="sphere" size="0.1" mass="1" condim="3" friction="1 0.005 0.002"/></body>
  </worldbody>
  <keyframe><key name="go" qpos="0 0 0.1 1 0 0 0  0 1 0.1 1 0 0 0  0 2 0.1 1 0 0 0"
                 qvel="0 0 0 0 0 10  1 0 0 0 10 0  1 0 0 0 10 0"/></keyframe>
</mujoco>)";

// torsional (condim 4) and rolling (condim 6) friction as MuJoCo's: a ball spinning on the spot slows as in
// MuJoCo; a ball rolling with condim 6 slows as in MuJoCo, one of condim 3 rolls on (both on elliptic cones)
TEST(SoftContacts, TorsionalAndRollingFrictionSlowAsInMujoco) {
  const std::string path = test::write_temp_file("spin_roll.xml", kSpinAndRoll);
  const MjModelPtr m(load_mujoco_model(path), mj_deleteModel);
  const MjDataPtr d(mj_makeData(m.get()), mj_deleteData);
  mj_resetDataKeyframe(m.get(), d.get(), 0);
  for (int k = 0; k < 250; ++k) mj_step(m.get(), d.get());
  ModelBuilder builder;
  const MujocoImport import = import_mjcf(builder, path);
  solver_test::Scene scene(builder);
  scene.state = scene.model.state("go");
  scene.run(0.5, 0.002);
  // the spin about Z (NovaPhy's free joint: [w_world; v]; MuJoCo's qvel: [v; w_body], the body turned about Z)
  const Scalar spin_mujoco = d->qvel[5], spin = scene.state.joint_qd[2];
  EXPECT_LT(spin_mujoco, 8);  // (it slowed: from 10 rad/s)
  EXPECT_NEAR(spin, spin_mujoco, 0.05 * (10 - spin_mujoco)) << "spin";
  // how far each ball rolled along X
  for (const char* name : {"roll6", "roll3"}) {
    const int b = mj_name2id(m.get(), mjOBJ_BODY, name);
    const Scalar mujoco = d->xpos[3 * b], novaphy = scene.position(import.body_map[b]).x();
    EXPECT_NEAR(novaphy, mujoco, 0.005) << name;
  }
  const Scalar rolled6 = scene.position(import.body_map[mj_name2id(m.get(), mjOBJ_BODY, "roll6")]).x();
  const Scalar rolled3 = scene.position(import.body_map[mj_name2id(m.get(), mjOBJ_BODY, "roll3")]).x();
  EXPECT_LT(rolled6, rolled3 - 0.01);  // rolling friction held it back
  // max_condim 3: neither torsional nor rolling rows, the spin kept (but for the angular damping) and the two
  // balls rolling alike
  SolverFeatherstoneSettings sliding_only;
  sliding_only.max_condim = 3;
  solver_test::Scene plain(builder, sliding_only);
  plain.state = plain.model.state("go");
  plain.run(0.5, 0.002);
  EXPECT_GT(plain.state.joint_qd[2], 9.5);
  const int roll6 = import.body_map[mj_name2id(m.get(), mjOBJ_BODY, "roll6")];
  const int roll3 = import.body_map[mj_name2id(m.get(), mjOBJ_BODY, "roll3")];
  EXPECT_NEAR(plain.position(roll6).x(), plain.position(roll3).x(), 1e-9);
  std::filesystem::remove(path);
}

// the torsional and rolling rows keep their impulse (contact_spin_impulse: an angular impulse along the rows'
// axes, none for condim 3) and the next step's rows start from it, spin included, on both routes: a step of no
// sweeps leaves each contact its warm start, all of the last impulses where the last sweeps converged and
// warmstarting_factor of them where they ran out
TEST(SoftContacts, SpinImpulsesAreKeptAndWarmStartTheirRows) {
  const std::string path = test::write_temp_file("spin_roll_warm.xml", kSpinAndRoll);
  ModelBuilder builder;
  const MujocoImport import = import_mjcf(builder, path);
  for (const bool blocks : {true, false}) {
    SolverFeatherstoneSettings settings;
    settings.use_batch_kernels = blocks;
    solver_test::Scene scene(builder, settings);
    scene.state = scene.model.state("go");
    scene.run(0.1, 0.002);
    const Contacts& C = scene.contacts;
    ASSERT_EQ(C.contact_count, 3);
    auto spin_of = [&](int c) { return Vec3(Eigen::Map<const Vec3>(&C.contact_spin_impulse[3 * c])); };
    for (int c = 0; c < C.contact_count; ++c) {
      const int ball = std::max(C.contact_body_a[c], C.contact_body_b[c]);
      const Vec3 spin = spin_of(c);
      if (ball == import.body_map[1]) {  // spinning about the normal (Z): torsion only
        EXPECT_GT(std::abs(spin.z()), 1e-6);
        EXPECT_LT(spin.head<2>().norm(), 1e-12 * std::abs(spin.z()));
      } else if (ball == import.body_map[2]) {  // rolling about Y: a rolling impulse about Y
        EXPECT_GT(std::abs(spin.y()), 1e-6);
      } else {
        EXPECT_EQ(spin, Vec3::Zero()) << "condim 3";
      }
    }
    // a step of no sweeps starts from all of the contacts' impulses, after sweeps that converged (to pgs_tolerance)
    // and after that step, whose sweeps ran out (warmstarting_factor is not a contact's: parts/contact_rows.h)
    scene.solver.settings.num_iterations = 0;
    for (const char* after : {"converged sweeps", "sweeps that ran out"}) {
      const std::vector<Scalar> impulse = C.contact_impulse, spin = C.contact_spin_impulse;
      scene.run(0.002, 0.002);
      // (to rounding: each vector is taken apart along the contact's frame and put together again)
      auto expect_all = [&](const std::vector<Scalar>& now, const std::vector<Scalar>& last, int c) {
        const Vec3 a = Eigen::Map<const Vec3>(&now[3 * c]), b = Eigen::Map<const Vec3>(&last[3 * c]);
        EXPECT_LE((a - b).norm(), 1e-12 * b.norm()) << (blocks ? "blocks" : "dense") << ", after " << after;
      };
      for (int c = 0; c < C.contact_count; ++c) {
        expect_all(C.contact_impulse, impulse, c);
        expect_all(C.contact_spin_impulse, spin, c);
      }
    }
  }
  std::filesystem::remove(path);
}

// solref outside MuJoCo's ranges and a solimp not finite are errors naming the geom
TEST(SoftContacts, BadSolrefAndSolimpNameTheShape) {
  ModelBuilder builder;
  const int body = builder.add_body(RigidBody::from_sphere(1, 0.1));
  ShapeOptions options;
  options.name = "foot";
  options.solref = {0.02, -1};
  EXPECT_NOVAPHY_ERROR(builder.add_shape_sphere(body, 0.1, options),
                       "shape 0 ('foot') (Sphere): solref must be (time constant > 0, damping ratio > 0), "
                       "(-stiffness < 0, -damping <= 0) or (0, 0) for a hard row, got (0.02, -1)");
  options.solref = {0.02, 1};
  options.solimp = {0.5, std::numeric_limits<Scalar>::infinity(), 0.001, 0.5, 2};
  EXPECT_NOVAPHY_ERROR(builder.add_shape_sphere(body, 0.1, options),
                       "shape 0 ('foot') (Sphere): solimp must be five finite numbers (dmin, dmax, width, midpoint, "
                       "power), got (0.5, inf, 0.001, 0.5, 2)");
  options.solimp = {0.9, 0.95, 0.001, 0.5, 2};
  options.margin = -0.01;
  EXPECT_NOVAPHY_ERROR(builder.add_shape_sphere(body, 0.1, options),
                       "shape 0 ('foot') (Sphere): margin must be finite and >= 0, got -0.01");
  EXPECT_NOVAPHY_ERROR(builder.set_impratio(0), "impratio must be finite and > 0, got 0");
}

}  // namespace
}  // namespace novaphy
