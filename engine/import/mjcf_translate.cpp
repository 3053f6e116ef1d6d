#include "engine/import/mjcf_translate.h"

#include <tinyxml2.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <initializer_list>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include "engine/model/error.h"

namespace novaphy {

namespace {

using tinyxml2::XMLDocument;
using tinyxml2::XMLElement;
using tinyxml2::XMLNode;

// MuJoCo >= 3 attributes with no translation here: element, attribute
constexpr const char* kUntranslated[][2] = {{"position", "timeconst"},
                                            {"intvelocity", "inheritrange"},
                                            {"joint", "actuatorgravcomp"},
                                            {"general", "actearly"},
                                            {"compiler", "alignfree"}};

std::string where(const std::string& file, const XMLElement* e) {
  return file + " line " + std::to_string(e->GetLineNum()) + ": <" + e->Name() + ">";
}

// attributes whose values are names, files or words, never numbers (a body may be named "inf")
const std::set<std::string> kTextAttributes = {
    "name",      "class",    "childclass", "file",         "prefix",    "meshdir",  "texturedir", "assetdir",
    "model",     "joint",    "joint1",     "joint2",       "body",      "body1",    "body2",      "site",
    "site1",     "site2",    "geom",       "geom1",        "geom2",     "mesh",     "material",   "texture",
    "hfield",    "tendon",   "tendon1",    "tendon2",      "target",    "objname",  "actuator",   "slidersite",
    "cranksite", "refsite",  "sidesite",   "camera",       "light",     "flex",     "skin",       "plugin",
    "instance",  "source",   "key",        "content_type", "fileright", "fileleft", "fileup",     "filedown",
    "filefront", "fileback", "link",       "filename"};

// a whole word strtod reads as a number
bool number(const std::string& word, double* x) {
  char* end = nullptr;
  *x = std::strtod(word.c_str(), &end);
  return !word.empty() && end == word.c_str() + word.size();
}

// why tinyxml2 could not read a file, in words
std::string xml_error(const XMLDocument& doc) {
  switch (doc.ErrorID()) {
    case tinyxml2::XML_ERROR_FILE_NOT_FOUND:
    case tinyxml2::XML_ERROR_FILE_COULD_NOT_BE_OPENED:
    case tinyxml2::XML_ERROR_FILE_READ_ERROR: return "the file cannot be read";
    case tinyxml2::XML_ERROR_EMPTY_DOCUMENT: return "the file is empty, not XML";
    case tinyxml2::XML_ERROR_MISMATCHED_ELEMENT: return "a closing tag that does not match the element it closes";
    case tinyxml2::XML_ERROR_PARSING_ELEMENT: return "an element that is malformed or not closed";
    case tinyxml2::XML_ERROR_PARSING_ATTRIBUTE: return "a malformed attribute";
    case tinyxml2::XML_ERROR_PARSING_TEXT: return "text outside any element (not an XML file?)";
    default: return "not well-formed XML";
  }
}

// the file as XML; Error naming the file and, in words, what is wrong with it
std::unique_ptr<XMLDocument> read_xml(const std::string& path) {
  if (std::filesystem::is_directory(path)) fail("cannot load '", path, "': a directory, not a file");
  auto doc = std::make_unique<XMLDocument>();
  if (doc->LoadFile(path.c_str()) != tinyxml2::XML_SUCCESS || !doc->RootElement())
    fail("cannot load '", path, "': XML parse error at line ", doc->ErrorLineNum(), ": ", xml_error(*doc));
  return doc;
}

// "file line 3: <body name="b"> pos="nan 0 1"", a keyframe's key with its index in the file
std::string attribute(const std::string& path, const XMLElement* e, const tinyxml2::XMLAttribute* a, int key) {
  std::string s = where(path, e);
  if (e->Attribute("name")) s.insert(s.size() - 1, std::string(" name=\"") + e->Attribute("name") + "\"");
  if (std::strcmp(e->Name(), "key") == 0) s += " (key " + std::to_string(key) + " of the file)";
  return s + " " + a->Name() + "=\"" + a->Value() + "\"";
}

// MuJoCo 2.2.2 reads a NaN as 0, drops it or keeps it, MuJoCo 4 keeps it: a NaN in a number is an Error, and so is an
// infinity outside a range (MJCF's range, ctrlrange, forcerange, ...; URDF's limits: both MuJoCos read "inf")
// and a zero quaternion (which MuJoCo 4 rejects); `user` data, which NovaPhy does not read, is left alone.
// `key`: the index in the file of a <key> element
void check_numbers(const std::string& path, const XMLElement* e, int key, bool urdf) {
  for (const tinyxml2::XMLAttribute* a = e->FirstAttribute(); a; a = a->Next()) {
    const std::string name = a->Name();
    if (kTextAttributes.count(name) || name == "user") continue;
    const bool range = (name.size() >= 5 && name.compare(name.size() - 5, 5, "range") == 0) ||
                       (urdf && (name == "lower" || name == "upper" || name == "effort" || name == "velocity"));
    std::istringstream words(a->Value());
    bool zero = true;
    int count = 0;
    for (std::string word; words >> word; ++count) {
      double x = 0;
      if (!number(word, &x)) break;
      zero = zero && x == 0;
      if (std::isnan(x)) fail(attribute(path, e, a, key), ": '", word, "' is not a number (NaN)");
      if (std::isinf(x) && !range)
        fail(attribute(path, e, a, key), ": '", word, "' is infinite (only a range's bounds may be)");
    }
    if (name == "quat" && zero && count == 4) fail(attribute(path, e, a, key), ": a zero quaternion");
  }
}

// every element below `e` (itself included), depth first
template <typename F>
void for_each_element(XMLElement* e, F&& f) {
  f(e);
  for (XMLElement* c = e->FirstChildElement(); c; c = c->NextSiblingElement()) for_each_element(c, f);
}

// a default class's attribute on its `tag` element, looked up the class and its ancestors (MuJoCo's defaults)
class Defaults {
 public:
  explicit Defaults(XMLElement* root) {
    for_each_element(root, [&](XMLElement* e) {
      if (std::strcmp(e->Name(), "default") != 0) return;
      const char* name = e->Attribute("class");
      classes_[name ? name : "main"] = e;
    });
  }
  const char* find(const char* cls, const char* tag, const char* attribute) const {
    const auto it = classes_.find(cls ? cls : "main");
    for (const XMLElement* d = it == classes_.end() ? nullptr : it->second; d && std::strcmp(d->Name(), "default") == 0;
         d = d->Parent()->ToElement())
      if (const XMLElement* t = d->FirstChildElement(tag); t && t->Attribute(attribute)) return t->Attribute(attribute);
    return nullptr;
  }

 private:
  std::map<std::string, XMLElement*> classes_;
};

// prints a document with each element on the line it was read from (an added one where it falls), so that
// MuJoCo's messages give the file's own line numbers
class LinePrinter : public tinyxml2::XMLPrinter {
 public:
  LinePrinter() : XMLPrinter(nullptr, true) {}

  bool VisitEnter(const XMLElement& e, const tinyxml2::XMLAttribute* a) override {
    const char* text = CStr();
    for (const int size = CStrSize() - 1; scanned_ < size; ++scanned_) line_ += text[scanned_] == '\n';
    for (; line_ < e.GetLineNum(); ++line_, ++scanned_) Putc('\n');
    return XMLPrinter::VisitEnter(e, a);
  }

 private:
  int line_ = 1, scanned_ = 0;  // the output's line, and how much of it was counted
};

class Translator {
 public:
  explicit Translator(TranslatedMjcf& out) : out_(out) {}

  void file(const std::string& path, bool main) {
    auto doc = read_xml(path);
    XMLElement* root = doc->RootElement();
    keys_ = 0;
    const std::string dir = std::filesystem::path(path).parent_path().string();
    Defaults defaults(root);
    for_each_element(root, [&](XMLElement* e) { element(path, e, defaults); });
    for (const auto& [e, a] : strip_) e->DeleteAttribute(a);
    strip_.clear();
    if (main && !has_autolimits_) autolimits(root, path);
    std::vector<std::string> includes;
    for_each_element(root, [&](XMLElement* e) {
      if (std::strcmp(e->Name(), "include") == 0 && e->Attribute("file"))
        includes.push_back((std::filesystem::path(main ? dir : main_dir_) / e->Attribute("file")).string());
    });
    if (main) main_dir_ = dir;
    add(path, *doc);
    for (const std::string& include : includes) file(include, false);
  }

 private:
  void element(const std::string& path, XMLElement* e, const Defaults& defaults) {
    for (const auto& [tag, attribute] : kUntranslated)
      if (std::strcmp(e->Name(), tag) == 0 && e->Attribute(attribute))
        fail(where(path, e), ": MuJoCo 3's attribute '", attribute,
             "' has no translation for MuJoCo 2.2.2's parser (docs/mjcf.md lists those that have)");
    if (std::strcmp(e->Name(), "compiler") == 0 && e->Attribute("autolimits")) has_autolimits_ = true;
    if (std::strcmp(e->Name(), "compiler") == 0 && e->Attribute("assetdir")) asset_dir(path, e);
    if (std::strcmp(e->Name(), "global") == 0 && e->Attribute("ellipsoidinertia")) {
      e->DeleteAttribute("ellipsoidinertia");
      note(path, e, "ellipsoidinertia (how the viewer draws inertias, no physics) -> dropped");
    }
    if (std::strcmp(e->Name(), "option") == 0 && e->Attribute("integrator", "implicitfast")) {
      e->SetAttribute("integrator", "implicit");
      note(path, e, "integrator=\"implicitfast\" -> \"implicit\"");
    }
    whitespace(path, e);
    if (std::strcmp(e->Name(), "key") == 0) ++keys_;
    check_numbers(path, e, keys_ - 1, false);
    if (std::strcmp(e->Name(), "joint") == 0)
      after_compiling(path, e, defaults, {"actuatorfrcrange", "actuatorfrclimited"}, out_.joint_force_range);
    if (std::strcmp(e->Name(), "body") == 0) after_compiling(path, e, defaults, {"gravcomp"}, out_.body_gravcomp);
    if (std::strcmp(e->Name(), "position") == 0) {
      after_compiling(path, e, defaults, {"inheritrange"}, out_.inherit_range);
      position_servo(path, e, defaults);
    }
  }

  // MuJoCo 3 attributes of a joint, actuator or body (on it or from its class: its own, else an ancestor's
  // childclass) that load_mujoco_model applies to the compiled model (by the element's name): taken out of
  // the file, their values (the first attribute's numbers, or nothing where the second says "false") kept in
  // `to`; in a default they are dropped once the file is read
  void after_compiling(const std::string& path, XMLElement* e, const Defaults& defaults,
                       std::initializer_list<const char*> attributes,
                       std::vector<std::pair<std::string, std::vector<double>>>& to) {
    const char* first = *attributes.begin();
    if (in_default(e)) {
      strip_after_file(e, attributes);
      return;
    }
    const char* cls = e->Attribute("class");
    for (const XMLNode* p = e->Parent(); !cls && p && p->ToElement(); p = p->Parent())
      cls = p->ToElement()->Attribute("childclass");
    auto value = [&](const char* a) { return e->Attribute(a) ? e->Attribute(a) : defaults.find(cls, e->Name(), a); };
    const char* numbers = value(first);
    const bool off = attributes.size() > 1 && value(attributes.begin()[1]) &&
                     std::strcmp(value(attributes.begin()[1]), "false") == 0;
    for (const char* a : attributes) e->DeleteAttribute(a);
    if (!numbers || off) return;
    if (!e->Attribute("name"))
      fail(where(path, e), ": MuJoCo 3's '", first, "' is applied after compiling, by name: name the <", e->Name(),
           ">");
    std::istringstream words(numbers);
    std::vector<double> x;
    for (double v; words >> v;) x.push_back(v);
    to.push_back({e->Attribute("name"), x});
    note(path, e, std::string(first) + "=\"" + numbers + "\" -> applied to the compiled model");
  }

  static bool in_default(const XMLElement* e) {
    return e->Parent() && e->Parent()->ToElement() && std::strcmp(e->Parent()->ToElement()->Name(), "default") == 0;
  }

  // a default's attributes, dropped once the file's elements have read them
  void strip_after_file(XMLElement* e, std::initializer_list<const char*> attributes) {
    for (const char* a : attributes)
      if (e->Attribute(a)) strip_.push_back({e, a});
  }

  // attribute values over several lines (keyframes) on one
  void whitespace(const std::string& path, XMLElement* e) {
    for (const tinyxml2::XMLAttribute* a = e->FirstAttribute(); a; a = a->Next()) {
      const std::string value = a->Value();
      if (value.find_first_of("\n\r\t") == std::string::npos) continue;
      std::istringstream words(value);
      std::string word, joined;
      while (words >> word) joined += (joined.empty() ? "" : " ") + word;
      const std::string name = a->Name();
      e->SetAttribute(name.c_str(), joined.c_str());
      note(path, e, name + " over several lines -> one");
      a = e->FindAttribute(name.c_str());
    }
  }

  // MuJoCo 3's position servo with kv or dampratio (on the element, else from its class): a general actuator of
  // gain kp and bias [0, -kp, -kv], or [0, -kp, dampratio] whose kv load_mujoco_model sets after compiling (out_
  // .dampratio); in a default, kv and dampratio are dropped once its actuators are rewritten
  void position_servo(const std::string& path, XMLElement* e, const Defaults& defaults) {
    if (in_default(e)) {
      strip_after_file(e, {"kv", "dampratio"});
      return;
    }
    const char* cls = e->Attribute("class");
    const char* kv = e->Attribute("kv");
    const char* ratio = kv ? nullptr : e->Attribute("dampratio");
    if (!kv && !ratio) kv = defaults.find(cls, "position", "kv");
    if (!kv && !ratio) ratio = defaults.find(cls, "position", "dampratio");
    if (!kv && !ratio) return;
    const char* kp_text = e->Attribute("kp") ? e->Attribute("kp") : defaults.find(cls, "position", "kp");
    const std::string kp = kp_text ? kp_text : "1";
    e->SetName("general");
    for (const char* a : {"kp", "kv", "dampratio"}) e->DeleteAttribute(a);
    e->SetAttribute("gaintype", "fixed");
    e->SetAttribute("biastype", "affine");
    e->SetAttribute("gainprm", kp.c_str());
    if (kv) {
      e->SetAttribute("biasprm", ("0 -" + kp + " -" + std::string(kv)).c_str());
      note(path, e, "position kp=" + kp + " kv=" + kv + " -> general gainprm, biasprm");
    } else {
      e->SetAttribute("biasprm", ("0 -" + kp + " " + std::string(ratio)).c_str());
      out_.dampratio = true;
      note(path, e,
           "position kp=" + kp + " dampratio=" + ratio + " -> general, kv from the inertia at qpos0 (MuJoCo 3's rule)");
    }
  }

  // MuJoCo 3 limits a joint or actuator that has a range (autolimits="true" is its default)
  void autolimits(XMLElement* root, const std::string& path) {
    XMLElement* compiler = root->FirstChildElement("compiler");
    if (!compiler) {
      compiler = root->GetDocument()->NewElement("compiler");
      root->InsertFirstChild(compiler);
    }
    compiler->SetAttribute("autolimits", "true");
    note(path, compiler, "autolimits=\"true\" (MuJoCo 3's default)");
  }

  // MuJoCo 3's assetdir: the meshdir and texturedir of a compiler that does not give its own
  void asset_dir(const std::string& path, XMLElement* compiler) {
    const std::string dir = compiler->Attribute("assetdir");
    compiler->DeleteAttribute("assetdir");
    for (const char* a : {"meshdir", "texturedir"})
      if (!compiler->Attribute(a)) compiler->SetAttribute(a, dir.c_str());
    note(path, compiler, "assetdir=\"" + dir + "\" -> meshdir and texturedir");
  }

  void note(const std::string& path, const XMLElement* e, const std::string& what) {
    out_.translations.push_back(std::filesystem::path(path).filename().string() + " line " +
                                std::to_string(e->GetLineNum()) + ": " + what);
  }

  void add(const std::string& path, XMLDocument& doc) {
    LinePrinter printer;
    doc.Print(&printer);
    const std::string name = std::filesystem::path(path).filename().string();
    if (mj_findFileVFS(out_.vfs.get(), name.c_str()) >= 0)
      fail("cannot load '", path, "': two included files are named '", name, "'");
    const int size = printer.CStrSize() - 1;
    if (mj_makeEmptyFileVFS(out_.vfs.get(), name.c_str(), size) != 0)
      fail("cannot load '", path, "': too many included files for MuJoCo's virtual file system");
    std::memcpy(out_.vfs->filedata[mj_findFileVFS(out_.vfs.get(), name.c_str())], printer.CStr(), size);
  }

  TranslatedMjcf& out_;
  std::vector<std::pair<XMLElement*, const char*>> strip_;  // attributes of defaults dropped after the file
  std::string main_dir_;
  bool has_autolimits_ = false;
  int keys_ = 0;  // the <key> elements of the file read so far
};

}  // namespace

void narrow_force_range(double lower, double upper, double gear, double* force_lower, double* force_upper) {
  if (gear == 0) return;
  const double a = lower / gear, b = upper / gear;
  *force_lower = std::max(*force_lower, std::min(a, b));
  *force_upper = std::min(*force_upper, std::max(a, b));
}

void apply_translation(mjModel* m, const TranslatedMjcf& translated) {
  if (translated.dampratio) set_dampratio(m);
  auto id = [&](mjtObj type, const std::string& name, const char* what) {
    const int i = mj_name2id(m, type, name.c_str());
    if (i < 0) fail("MuJoCo 3's ", what, " of '", name, "': no such element in the compiled model");
    return i;
  };
  // a joint's actuatorfrcrange: the force range of the one actuator on it, over its gear
  for (const auto& [name, range] : translated.joint_force_range) {
    const int j = id(mjOBJ_JOINT, name, "actuatorfrcrange");
    if (range.size() != 2) fail("joint '", name, "': actuatorfrcrange needs two numbers");
    std::vector<int> on;
    for (int u = 0; u < m->nu; ++u)
      if (m->actuator_trntype[u] == mjTRN_JOINT && m->actuator_trnid[2 * u] == j) on.push_back(u);
    if (on.size() > 1)
      fail("joint '", name, "': actuatorfrcrange with ", on.size(),
           " actuators on it has no MuJoCo 2.2.2 equivalent (one actuator: its force range)");
    if (on.empty() || m->actuator_gear[6 * on[0]] == 0) continue;
    const int u = on[0];
    mjtNum* limit = m->actuator_forcerange + 2 * u;
    if (!m->actuator_forcelimited[u]) limit[0] = -std::numeric_limits<mjtNum>::infinity(), limit[1] = -limit[0];
    narrow_force_range(range[0], range[1], m->actuator_gear[6 * u], limit, limit + 1);
    m->actuator_forcelimited[u] = 1;
  }
  // a position servo's inheritrange: its control range the target's range about its middle, scaled
  for (const auto& [name, factor] : translated.inherit_range) {
    const int u = id(mjOBJ_ACTUATOR, name, "inheritrange"), target = m->actuator_trnid[2 * u];
    const bool joint = m->actuator_trntype[u] == mjTRN_JOINT, tendon = m->actuator_trntype[u] == mjTRN_TENDON;
    const mjtNum* range = joint ? m->jnt_range + 2 * target : tendon ? m->tendon_range + 2 * target : nullptr;
    if (!range || !(joint ? m->jnt_limited[target] : m->tendon_limited[target]))
      fail("actuator '", name, "': inheritrange needs a joint or tendon with a range");
    if (factor.empty() || factor[0] <= 0) continue;
    const mjtNum middle = (range[0] + range[1]) / 2, half = factor[0] * (range[1] - range[0]) / 2;
    m->actuator_ctrlrange[2 * u] = middle - half;
    m->actuator_ctrlrange[2 * u + 1] = middle + half;
    m->actuator_ctrllimited[u] = 1;
  }
}

std::vector<double> translated_gravcomp(const mjModel* m, const TranslatedMjcf& translated) {
  if (translated.body_gravcomp.empty()) return {};
  std::vector<double> gravcomp(m->nbody, 0);
  for (const auto& [name, value] : translated.body_gravcomp) {
    const int b = mj_name2id(m, mjOBJ_BODY, name.c_str());
    if (b < 0) fail("MuJoCo 3's gravcomp of '", name, "': no such body in the compiled model");
    if (value.size() != 1) fail("body '", name, "': gravcomp needs one number");
    gravcomp[b] = value[0];
  }
  return gravcomp;
}

void set_dampratio(mjModel* m) {
  const std::unique_ptr<mjData, void (*)(mjData*)> d(mj_makeData(m), mj_deleteData);
  mju_copy(d->qpos, m->qpos0, m->nq);
  mj_fwdPosition(m, d.get());
  std::vector<mjtNum> x(m->nv);
  for (int u = 0; u < m->nu; ++u) {
    const mjtNum kp = m->actuator_gainprm[mjNGAIN * u];
    mjtNum* bias = m->actuator_biasprm + mjNBIAS * u;
    if (kp != -bias[1] || bias[2] <= 0) continue;
    const mjtNum* moment = d->actuator_moment + static_cast<size_t>(u) * m->nv;
    mj_solveM(m, d.get(), x.data(), moment, 1);
    const mjtNum inverse_mass = mju_dot(moment, x.data(), m->nv);
    const mjtNum mass = inverse_mass > mjMINVAL ? 1 / inverse_mass : 0;
    bias[2] = -2 * bias[2] * std::sqrt(kp * mass);
  }
}

TranslatedMjcf translate_mjcf(const std::string& path) {
  TranslatedMjcf out;
  out.vfs = {new mjVFS, [](mjVFS* vfs) {
               mj_deleteVFS(vfs);
               delete vfs;
             }};
  mj_defaultVFS(out.vfs.get());
  Translator(out).file(path, true);
  return out;
}

void check_urdf(const std::string& path) {
  const auto doc = read_xml(path);
  for_each_element(doc->RootElement(), [&](XMLElement* e) { check_numbers(path, e, -1, true); });
}

}  // namespace novaphy
