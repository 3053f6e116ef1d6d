// A model's sensors (model.h's SensorType) computed as MuJoCo computes its sensordata in mj_step: from the state
// a step starts from, with that step's accelerations and the contact forces it applied. The step's solver calls
// evaluate after it stepped; the values go to State::sensor_data, world after world.
#pragma once

#include <vector>

#include "engine/collision/pipeline.h"
#include "engine/model/model.h"

namespace novaphy {

class Sensors {
 public:
  explicit Sensors(const Model& model);
  bool empty() const { return model_.sensor_count == 0; }

  // sensor_data from the coordinates q and velocities qd a step of dt started from, the velocities qd_next it
  // ended with (the step's accelerations (qd_next - qd) / dt), the applied wrenches body_f and the contacts with
  // the impulses the step applied; each world on one of `threads` threads
  void evaluate(const Scalar* q, const Scalar* qd, const Scalar* qd_next, const Scalar* body_f,
                const Contacts& contacts, Scalar dt, Scalar* sensor_data, int threads);

 private:
  // what a world's sensors need: its sensors [sensor_begin, sensor_end), the articulations their bodies are in
  struct WorldSensors {
    int sensor_begin = 0, sensor_end = 0;
    std::vector<int> articulations;
    bool dynamics = false;  // some sensor reads accelerations or forces
  };
  // a thread's scratch: each articulation's kinematics, the wrenches on its bodies, its accelerations
  struct Scratch {
    std::vector<ArticulationScratch> arts;
    std::vector<Scalar> wrench, qdd, tau;
    std::vector<int> contacts;  // the world's contacts
  };
  void evaluate_world(int w, const Scalar* q, const Scalar* qd, const Scalar* qd_next, const Scalar* body_f,
                      const Contacts& contacts, Scalar dt, Scalar* sensor_data, Scratch& scratch) const;

  const Model& model_;
  std::vector<WorldSensors> worlds_;
  std::vector<int> body_art_, body_link_;                          // per body: its articulation and link
  std::vector<Scratch> scratch_;                                   // per thread
  bool contacts_ = false;                                          // some sensor reads the contacts
  std::vector<int> contact_start_, contact_order_, contact_next_;  // the contacts by world (group_by_key)
};

}  // namespace novaphy
