// The main job: loads MJCF scenes into NovaPhy and MuJoCo, runs forward dynamics in both at random
// states (contacts and limits off) and prints the largest relative differences.
//   novaphy_validate [--states N] [scene.xml ...]   (default: humanoid.xml and the 15-link chain)
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "engine/model/error.h"
#include "tools/mujoco_oracle.h"

int main(int argc, char** argv) {
  int states = 100;
  std::vector<std::string> scenes;
  for (int k = 1; k < argc; ++k) {
    const std::string arg = argv[k];
    if (arg == "--states" && k + 1 < argc)
      states = std::atoi(argv[++k]);
    else
      scenes.push_back(arg);
  }
  if (scenes.empty()) scenes = {"/usr/share/mujoco/model/humanoid/humanoid.xml", NOVAPHY_SCENE_DIR "/chain15.xml"};

  std::printf("%-16s %5s %5s | %-9s %-9s %-9s %-9s %-9s %-9s %-9s\n", "scene", "dofs", "states", "pose", "velocity",
              "H", "bias", "qdd CRBA", "qdd ABA", "qdd batch");
  novaphy::Scalar worst = 0;
  std::mt19937 rng(2026);
  for (const std::string& scene : scenes) {
    try {
      novaphy::MujocoOracle oracle(scene);
      novaphy::OracleErrors e;
      for (int s = 0; s < states; ++s) e.accumulate(oracle.compare_random_state(rng));
      const std::string name = scene.substr(scene.find_last_of('/') + 1);
      std::printf("%-16s %5d %5d | %.3e %.3e %.3e %.3e %.3e %.3e %.3e\n", name.c_str(), oracle.model().joint_dof_count,
                  states, e.body_pose, e.body_velocity, e.mass_matrix, e.bias, e.qdd_crba, e.qdd_aba, e.qdd_batched);
      worst = std::max(worst, e.max());
    } catch (const novaphy::Error& error) {
      std::fprintf(stderr, "novaphy_validate: %s\n", error.what());
      return 2;
    }
  }
  std::printf("largest relative difference NovaPhy vs MuJoCo 2.2.2: %.3e (%s 1e-9)\n", worst,
              worst <= 1e-9 ? "within" : "ABOVE");
  return worst <= 1e-9 ? 0 : 1;
}
