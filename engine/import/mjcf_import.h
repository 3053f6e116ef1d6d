// MJCF and URDF import through MuJoCo's own parser (mj_loadXML), and the maps between the
// coordinates of an imported mjModel and the NovaPhy model built from it.
//   MuJoCo body with k joints -> a chain of k links, the first k-1 massless, the last with the mass
//   body with no joint        -> a Fixed joint to its parent (static geometry when welded to the world)
//   hinge / slide / ball / free -> Revolute / Prismatic / Ball / Free, q identical except quaternion
//   order ([w x y z] -> [x y z w]) and the Free velocity ([v; w_body] -> [w_world; v])
//   motor, position, velocity, general (fixed gain, affine bias) on a hinge or slide -> add_actuator,
//   on a fixed tendon -> add_tendon_actuator
//   connect, weld and joint equalities (active ones) -> add_connect, add_weld, add_joint_coupling
//   fixed tendon over hinges and slides (stiffness, damping, springlength, range) -> add_tendon
//   sensors NovaPhy computes (model.h's SensorType) -> add_sensor, on the site's, geom's or body's frame
#pragma once

#include <mujoco/mujoco.h>

#include <string>
#include <vector>

#include "engine/import/mujoco_fields.h"
#include "engine/model/builder.h"

namespace novaphy {

struct MujocoJoint {
  int type = 0, qposadr = 0, dofadr = 0;  // MuJoCo's jnt_type, jnt_qposadr, jnt_dofadr
  int q = 0, qd = 0;  // its first NovaPhy coordinate and dof, from q_begin / qd_begin (the order the import added it)
};

// what an import made, and the maps between the MuJoCo model's state and NovaPhy's (qpos and qvel of the
// imported model alone; joint_q and joint_qd of the whole builder's model)
struct MujocoImport {
  std::vector<std::string> warnings;  // everything in the file that changes the motion and is not modelled, by name
  std::vector<int> body_map;          // MuJoCo body id -> NovaPhy body (-1: the world or welded to it)
  std::vector<int> actuator_map;      // MuJoCo actuator id -> NovaPhy motor (-1: not imported)
  std::vector<int> sensor_map;        // MuJoCo sensor id -> the builder's sensor (-1: not computed, in warnings)
  int q_begin = 0;                    // first NovaPhy coordinate / dof of the imported joints
  int qd_begin = 0;
  int nq = 0, nv = 0;               // the MuJoCo model's
  std::vector<MujocoJoint> joints;  // the MuJoCo model's joints

  // NovaPhy joint_q / joint_qd (entries q_begin.. / qd_begin..) from MuJoCo's qpos / qvel, and back
  void to_joint_q(const mjtNum* qpos, Scalar* joint_q) const;
  void to_joint_qd(const mjtNum* qpos, const mjtNum* qvel, Scalar* joint_qd) const;
  void to_qpos(const Scalar* joint_q, mjtNum* qpos) const;
  void to_qvel(const mjtNum* qpos, const Scalar* joint_qd, mjtNum* qvel) const;
  // T (nv x nv) with qd = T qvel and qdd = T qacc; H_mujoco = T^T H T, bias_mujoco = T^T bias
  MatX velocity_map(const mjtNum* qpos) const;
};

// MuJoCo 2.2.2's mjtSensor value of the sensor type of that name ("mjSENS_GYRO") among those NovaPhy computes, -1
// for any other (a compiled model of another version names its types; their values differ)
int mujoco_sensor_type(const std::string& name);

// loads an MJCF or URDF file; throws Error with MuJoCo's message when it does not exist or parse. body_gravcomp
// (where given): MuJoCo 3's body gravcomp by body id, which MuJoCo 2.2.2's model has no field for (empty where the
// file gives none)
mjModel* load_mujoco_model(const std::string& path, std::vector<double>* body_gravcomp = nullptr);

// the one converter: a compiled model of any MuJoCo version, as a view of its fields
MujocoImport import_mujoco_fields(ModelBuilder& builder, const MujocoFields& m, const ImportOptions& options = {});
MujocoImport import_mujoco_model(ModelBuilder& builder, const mjModel* m, const ImportOptions& options = {});
MujocoImport import_mjcf(ModelBuilder& builder, const std::string& path, const ImportOptions& options = {});

}  // namespace novaphy
