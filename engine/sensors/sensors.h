// A model's sensors (model.h's SensorType) computed as MuJoCo computes its sensordata in mj_step: from the state
// a step starts from, with that step's accelerations and the contact forces it applied. The step's solver calls
// read_start before it steps (what the start state alone decides: joint and tendon values, the frames' poses and
// velocities, from the state's joint and body arrays) and evaluate after it (contact forces, accelerations, joint
// forces); the values go to State::sensor_data, world after world.
#pragma once

#include <vector>

#include "engine/collision/pipeline.h"
#include "engine/model/model.h"

namespace novaphy {

class Sensors {
 public:
  explicit Sensors(const Model& model);
  bool empty() const { return model_.sensor_count == 0; }
  // some sensor reads accelerations or forces: evaluate then reads the start's joint_q and joint_qd
  bool reads_dynamics() const { return dynamics_; }

  // what the start state of a step decides, from its joint_q and joint_qd and its bodies' body_q and body_qd (their
  // forward kinematics as the step before or a reset left them, and as collide read them); each world on one of
  // `threads` threads. Writes the sensors' scratch only
  void read_start(const State& start, int threads);
  // sensor_data after a step of dt from the start read_start read: the velocities qd_next it ended with, the applied
  // wrenches body_f and the contacts with the impulses the step applied; where reads_dynamics, the start's
  // coordinates q and velocities qd (the step's accelerations (qd_next - qd) / dt, and the inverse dynamics at
  // them); each world on one of `threads` threads
  void evaluate(const Scalar* q, const Scalar* qd, const Scalar* qd_next, const Scalar* body_f,
                const Contacts& contacts, Scalar dt, Scalar* sensor_data, int threads);

 private:
  // what a world's sensors need: its sensors [sensor_begin, sensor_end), the articulations whose accelerations or
  // forces they read
  struct WorldSensors {
    int sensor_begin = 0, sensor_end = 0;
    std::vector<int> articulations;
    bool dynamics = false;  // some sensor reads accelerations or forces
  };
  // a thread's scratch: each articulation's kinematics, the wrenches on its bodies, its accelerations
  struct Scratch {
    std::vector<ArticulationScratch> arts;
    std::vector<Scalar> wrench, qdd, tau;
  };
  void read_world_start(int w, const State& start);
  void evaluate_world(int w, const Scalar* q, const Scalar* qd, const Scalar* qd_next, const Scalar* body_f,
                      const Contacts& contacts, Scalar dt, Scalar* sensor_data, Scratch& scratch) const;

  const Model& model_;
  std::vector<WorldSensors> worlds_;
  std::vector<int> body_art_, body_link_;                          // per body: its articulation and link
  std::vector<Scratch> scratch_;                                   // per thread
  bool contacts_ = false, dynamics_ = false;                       // some sensor reads the contacts, the dynamics
  std::vector<int> contact_start_, contact_order_, contact_next_;  // the contacts by world (group_by_key)
  std::vector<Scalar> start_values_;  // per sensor value: what read_start found (for the sensors it decides)
  std::vector<Transform> frame_;      // per sensor: a touch or contactforce sensor's frame in the world at the start
};

}  // namespace novaphy
