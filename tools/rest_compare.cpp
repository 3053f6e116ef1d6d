// One world of an MJCF file stepped by MuJoCo 2.2.2 and by NovaPhy from the same start (a keyframe, or qpos0)
// with the keyframe's controls held; prints named bodies' positions in both engines and the distance between
// them: where a robot comes to rest in each.
//   novaphy_rest_compare scene.xml [--keyframe NAME] [--seconds S] body [body ...]
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "engine/collision/pipeline.h"
#include "engine/import/mjcf_import.h"
#include "engine/model/builder.h"
#include "engine/model/error.h"
#include "engine/solver/solver_featherstone.h"

using namespace novaphy;

int main(int argc, char** argv) {
  std::string path, keyframe;
  double seconds = 2;
  std::vector<std::string> bodies;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--keyframe" && i + 1 < argc)
      keyframe = argv[++i];
    else if (arg == "--seconds" && i + 1 < argc)
      seconds = std::atof(argv[++i]);
    else if (path.empty())
      path = arg;
    else
      bodies.push_back(arg);
  }
  if (path.empty() || bodies.empty()) {
    std::fprintf(stderr, "usage: novaphy_rest_compare scene.xml [--keyframe NAME] [--seconds S] body [body ...]\n");
    return 2;
  }
  try {
    const std::unique_ptr<mjModel, void (*)(mjModel*)> m(load_mujoco_model(path), mj_deleteModel);
    const std::unique_ptr<mjData, void (*)(mjData*)> d(mj_makeData(m.get()), mj_deleteData);
    ModelBuilder builder;
    const MujocoImport import = import_mjcf(builder, path);
    const Model model = builder.finalize();
    if (!keyframe.empty()) mj_resetDataKeyframe(m.get(), d.get(), model.keyframe(keyframe));
    State state = keyframe.empty() ? model.state() : model.state(keyframe);
    const Control control = keyframe.empty() ? model.control() : model.control(keyframe);
    const int steps = static_cast<int>(seconds / m->opt.timestep + 0.5);
    for (int k = 0; k < steps; ++k) mj_step(m.get(), d.get());
    CollisionPipeline pipeline(model);
    Contacts contacts = pipeline.contacts();
    SolverFeatherstone solver(model);
    for (int k = 0; k < steps; ++k) {
      pipeline.collide(state, contacts);
      solver.step(state, state, control, contacts, m->opt.timestep);
    }
    std::printf("%s after %g s (%d steps of %g s): contacts MuJoCo %d, NovaPhy %d\n", path.c_str(), seconds, steps,
                m->opt.timestep, d->ncon, contacts.contact_count);
    for (const std::string& name : bodies) {
      const int b = mj_name2id(m.get(), mjOBJ_BODY, name.c_str());
      if (b < 0 || import.body_map[b] < 0) fail("no moving body '", name, "' in ", path);
      const Vec3 mujoco(d->xpos[3 * b], d->xpos[3 * b + 1], d->xpos[3 * b + 2]);
      const Vec3 novaphy = Eigen::Map<const Vec3>(&state.body_q[7 * import.body_map[b]]);
      std::printf("%-16s MuJoCo %9.5f %9.5f %9.5f   NovaPhy %9.5f %9.5f %9.5f   apart %.2f mm\n", name.c_str(),
                  mujoco.x(), mujoco.y(), mujoco.z(), novaphy.x(), novaphy.y(), novaphy.z(),
                  1000 * (novaphy - mujoco).norm());
    }
  } catch (const Error& e) {
    std::fprintf(stderr, "novaphy_rest_compare: %s\n", e.what());
    return 1;
  }
  return 0;
}
