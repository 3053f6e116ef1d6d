// libFuzzer target: random MJCF (nested bodies, every joint and geom type, odd and invalid numbers)
// through MuJoCo's parser into ModelBuilder, then forward dynamics and a few steps. Errors must be
// novaphy::Error; a crash, a sanitizer report or any other exception is a finding.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>

#include "engine/eval/eval.h"
#include "engine/import/mjcf_import.h"
#include "engine/model/error.h"
#include "engine/solver/solver_featherstone.h"
#include "fuzz_support.h"

using namespace novaphy;

namespace {

std::string text(Scalar x) {
  std::ostringstream os;
  os.precision(17);
  os << x;
  return os.str();
}

std::string triple(FuzzedDataProvider& data) {
  return text(fuzz::number(data)) + " " + text(fuzz::number(data)) + " " + text(fuzz::number(data));
}

std::string mjcf(FuzzedDataProvider& data) {
  std::ostringstream xml;
  xml << "<mujoco><option gravity=\"" << triple(data) << "\"/>";
  // a mesh of a few points, flat, repeated or not finite at times
  xml << "<asset><mesh name=\"m\" vertex=\"";
  for (int k = 0, n = data.ConsumeIntegralInRange(1, 8); k < n; ++k) xml << triple(data) << " ";
  xml << "\"/></asset><worldbody>";
  if (data.ConsumeBool()) xml << "<geom type=\"plane\" size=\"5 5 0.1\"/>";
  const char* joints[] = {"hinge", "slide", "ball", "free"};
  const char* geoms[] = {"sphere", "capsule", "box", "plane", "cylinder", "ellipsoid", "mesh"};
  std::function<void(int)> body = [&](int depth) {
    xml << "<body pos=\"" << triple(data) << "\"";
    if (data.ConsumeBool()) xml << " quat=\"" << text(fuzz::number(data)) << " " << triple(data) << "\"";
    xml << ">";
    for (int k = 0, n = data.ConsumeIntegralInRange(0, 3); k < n; ++k) {
      xml << "<joint type=\"" << joints[data.ConsumeIntegralInRange(0, 3)] << "\" pos=\"" << triple(data)
          << "\" axis=\"" << triple(data) << "\"";
      if (data.ConsumeBool()) xml << " damping=\"" << text(fuzz::number(data)) << "\"";
      if (data.ConsumeBool()) xml << " limited=\"true\" range=\"" << text(fuzz::number(data)) << " 1\"";
      xml << "/>";
    }
    if (data.ConsumeBool())
      xml << "<inertial pos=\"" << triple(data) << "\" mass=\"" << text(fuzz::number(data)) << "\" diaginertia=\""
          << triple(data) << "\"/>";
    for (int k = 0, n = data.ConsumeIntegralInRange(0, 2); k < n; ++k)
      xml << "<geom type=\"" << geoms[data.ConsumeIntegralInRange(0, 6)] << "\" mesh=\"m\" size=\"" << triple(data)
          << "\" solref=\"" << text(fuzz::number(data)) << " " << text(fuzz::number(data)) << "\" solimp=\""
          << triple(data) << " 0.5 2\" margin=\"" << text(fuzz::number(data)) << "\"/>";
    if (depth < 4)
      for (int k = 0, n = data.ConsumeIntegralInRange(0, 2); k < n; ++k) body(depth + 1);
    xml << "</body>";
  };
  for (int k = 0, n = data.ConsumeIntegralInRange(0, 3); k < n; ++k) body(0);
  xml << "</worldbody></mujoco>";
  return xml.str();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* bytes, std::size_t size) {
  FuzzedDataProvider data(bytes, size);
  static const std::string path = "/tmp/novaphy_fuzz_mjcf_" + std::to_string(getpid()) + ".xml";
  std::ofstream(path) << mjcf(data);
  try {
    ModelBuilder builder;
    import_mjcf(builder, path);
    const Model model = builder.finalize();
    State state = model.state();
    eval_forward_dynamics(model, state, model.control());
    if (model.articulation_count > 0) {
      CollisionPipeline pipeline(model);
      Contacts contacts = pipeline.contacts();
      SolverFeatherstone solver(model);
      for (int k = 0; k < 3; ++k) {
        pipeline.collide(state, contacts);
        solver.step(state, state, model.control(), contacts, 0.01);
      }
    }
  } catch (const Error&) {
  }
  return 0;
}
