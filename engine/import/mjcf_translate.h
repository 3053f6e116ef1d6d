// MuJoCo >= 3 MJCF through MuJoCo 2.2.2's parser (the reference NovaPhy imports with): the file and its
// <include>s read, the newer syntax today's MuJoCo Menagerie files use rewritten into its 2.2.2 equivalent
// (docs/mjcf.md lists each), and the translated files handed to mj_loadXML in memory (a virtual file system);
// meshes and other assets are still read from disk. A newer attribute it does not translate is an Error
// naming it, its element, file and line.
#pragma once

#include <mujoco/mujoco.h>

#include <memory>
#include <string>
#include <vector>

namespace novaphy {

struct TranslatedMjcf {
  std::unique_ptr<mjVFS, void (*)(mjVFS*)> vfs{nullptr, nullptr};  // the translated files, by base name
  std::vector<std::string> translations;                           // what was rewritten, one line each
  // a position servo's dampratio is carried as a positive biasprm[2]: set_dampratio turns it into its kv
  bool dampratio = false;
  // by name: joints' actuatorfrcrange [lower, upper], position servos' inheritrange [factor] and bodies' gravcomp
  // [share], taken out
  std::vector<std::pair<std::string, std::vector<double>>> joint_force_range, inherit_range, body_gravcomp;
};

// the translated attributes that need the compiled model, applied to it (after mj_loadXML): set_dampratio;
// a joint's actuatorfrcrange as the force range of its one actuator over the gear (intersected with the
// actuator's own; Error for several actuators); a servo's inheritrange as its control range, the joint's or
// tendon's range scaled about its middle (Error without a range)
void apply_translation(mjModel* m, const TranslatedMjcf& translated);

// MuJoCo 3's body gravcomp by body id of the compiled model (empty where the file gives none); Error for a body
// name the model lacks or a gravcomp that is not one number
std::vector<double> translated_gravcomp(const mjModel* m, const TranslatedMjcf& translated);

// MuJoCo 3's joint actuatorfrcrange [lower, upper] as the force range of the joint's one actuator, of gear
// `gear`: intersected with the actuator's own [*force_lower, *force_upper] (both routes of the import use it)
void narrow_force_range(double lower, double upper, double gear, double* force_lower, double* force_upper);

// today's MuJoCo's damping of a position servo given by a ratio (gain kp = -biasprm[1], biasprm[2] > 0 the
// ratio; the rule of MuJoCo >= 3.15): kv = 2 ratio sqrt(kp m), m = (J M^-1 J^T)^-1 the inertia its transmission
// J moves at qpos0 (off-diagonal coupling included), written as biasprm[2] = -kv
void set_dampratio(mjModel* m);

// reads `path` (MJCF) and its includes and translates them; throws Error for a MuJoCo >= 3 attribute without a
// translation, for a file that is not well-formed XML or a directory (in words, not tinyxml2's codes), and for a
// number MuJoCo 2.2.2 would misread: a NaN, an infinity outside a range, a zero quaternion (naming the file,
// line, element and attribute, with the value as written)
TranslatedMjcf translate_mjcf(const std::string& path);

// the same checks of a URDF file, which is not translated (its limits may be infinite)
void check_urdf(const std::string& path);

}  // namespace novaphy
