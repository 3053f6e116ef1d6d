// Per-world parameters at run time: the Model fields learning randomises, what each one counts per world, the
// checks a value passes, and Model::set_parameter, which writes them for some worlds and marks those worlds
// changed (a solver rereads what depends on them at its next step: SolverFeatherstone::read_parameters).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <sstream>
#include <string>

#include "engine/model/builder_checks.h"
#include "engine/model/error.h"
#include "engine/model/group_by_key.h"
#include "engine/model/model.h"

namespace novaphy {

namespace {

// what a parameter's entries run over: a world's bodies, dofs, shapes or actuators, or the world itself
enum class Over { Body, Dof, Shape, Actuator, World };

// the check each value passes: Finite; NotNegative; Body (the body's mass, centre of mass and inertia together
// a body's, check_rigid_body); Lower / Upper (the range with the partner field's entry: lower <= upper, no NaN);
// Integer (a whole number, for an int field)
enum class Check { Finite, NotNegative, Body, Lower, Upper, Integer };

struct Parameter {
  const char* name;
  Over over;
  int width;
  Check check;
  std::vector<Scalar> Model::*real;     // the field (nullptr for an int field)
  std::vector<int> Model::*whole;       // the int field
  std::vector<Scalar> Model::*partner;  // Lower / Upper: the other end of the range
};

#define NOVAPHY_REAL(name, over, width, check) \
  { #name, Over::over, width, Check::check, &Model::name, nullptr, nullptr }
#define NOVAPHY_RANGE(name, over, check, partner) \
  { #name, Over::over, 1, Check::check, &Model::name, nullptr, &Model::partner }
const Parameter kParameters[] = {
    NOVAPHY_REAL(body_mass, Body, 1, Body),
    NOVAPHY_REAL(body_com, Body, 3, Finite),
    NOVAPHY_REAL(body_inertia, Body, 9, Body),
    NOVAPHY_REAL(joint_armature, Dof, 1, NotNegative),
    NOVAPHY_REAL(joint_damping, Dof, 1, NotNegative),
    NOVAPHY_REAL(joint_frictionloss, Dof, 1, NotNegative),
    NOVAPHY_REAL(joint_stiffness, Dof, 1, NotNegative),
    // (the shape fields here are those SolverModel::read_parameters reads again into the contact materials)
    NOVAPHY_REAL(shape_mu, Shape, 1, NotNegative),
    NOVAPHY_REAL(shape_mu_torsion, Shape, 1, NotNegative),
    NOVAPHY_REAL(shape_mu_rolling, Shape, 1, NotNegative),
    {"shape_priority", Over::Shape, 1, Check::Integer, nullptr, &Model::shape_priority, nullptr},
    NOVAPHY_REAL(actuator_gain, Actuator, 1, NotNegative),
    NOVAPHY_REAL(actuator_bias, Actuator, 3, Finite),
    NOVAPHY_RANGE(actuator_ctrl_lower, Actuator, Lower, actuator_ctrl_upper),
    NOVAPHY_RANGE(actuator_ctrl_upper, Actuator, Upper, actuator_ctrl_lower),
    NOVAPHY_RANGE(actuator_force_lower, Actuator, Lower, actuator_force_upper),
    NOVAPHY_RANGE(actuator_force_upper, Actuator, Upper, actuator_force_lower),
    NOVAPHY_REAL(world_gravity, World, 3, Finite),
};
#undef NOVAPHY_REAL
#undef NOVAPHY_RANGE

const char* over_name(Over over) {
  switch (over) {
    case Over::Body: return "bodies";
    case Over::Dof: return "dofs";
    case Over::Shape: return "shapes";
    case Over::Actuator: return "actuators";
    case Over::World: return "entries";
  }
  return "";
}

// the joint whose dofs include dof `dof`
int dof_joint(const Model& model, int dof) {
  return static_cast<int>(std::upper_bound(model.joint_qd_start.begin(), model.joint_qd_start.end(), dof) -
                          model.joint_qd_start.begin()) -
         1;
}

// the world of each entry a parameter runs over (-1: none, as a static shape's)
std::vector<int> entry_worlds(const Model& model, Over over) {
  auto joint_world = [&](int j) { return model.body_world[model.joint_child[j]]; };
  std::vector<int> world;
  switch (over) {
    case Over::Body: return model.body_world;
    case Over::Shape: return model.shape_world;
    case Over::World:
      world.resize(model.world_count);
      for (int w = 0; w < model.world_count; ++w) world[w] = w;
      return world;
    case Over::Dof:
      world.resize(model.joint_dof_count);
      for (int j = 0; j < model.joint_count; ++j)
        std::fill(world.begin() + model.joint_qd_start[j], world.begin() + model.joint_qd_start[j + 1], joint_world(j));
      return world;
    case Over::Actuator:
      world.resize(model.actuator_count);
      for (int u = 0; u < model.actuator_count; ++u) {
        const int j = model.actuator_joint[u], t = model.actuator_tendon[u];
        if (j >= 0) {
          world[u] = joint_world(j);
        } else if (model.actuator_body[u] >= 0) {
          world[u] = model.body_world[model.actuator_body[u]];
        } else {
          world[u] = model.tendon_world(t);
        }
      }
      return world;
  }
  return world;
}

// the parameter of that name; throws Error naming the parameters for any other
const Parameter& parameter(const std::string& field) {
  for (const Parameter& p : kParameters)
    if (field == p.name) return p;
  std::string names;
  for (const Parameter& p : kParameters) names += (names.empty() ? "" : ", ") + std::string(p.name);
  fail("set_parameter: '", field, "' is not a per-world parameter (the model's structure stays as finalized); ",
       "the parameters are: ", names);
}

// the entries of each world in the model's order: world w's are entries[start[w] .. start[w + 1])
struct WorldEntries {
  std::vector<int> start, entries;
  WorldEntries() = default;
  WorldEntries(const Model& model, Over over) {
    const std::vector<int> world_of = entry_worlds(model, over);
    start.resize(model.world_count + 1);
    entries.resize(world_of.size());
    std::vector<int> next(model.world_count + 1);
    group_by_key(
        static_cast<int>(world_of.size()), model.world_count, [&](int i) { return world_of[i]; }, start.data(),
        entries.data(), next.data());
    entries.resize(start[model.world_count]);
  }
};

void check_world(const Model& model, const std::string& field, int w) {
  if (w < 0 || w >= model.world_count)
    fail("set_parameter ", field, ": world id ", w, " out of range [0, ", model.world_count, ")");
}

std::string entry_label(const Model& model, Over over, int i) {
  switch (over) {
    case Over::Body: return label("body", i, model.body_name[i]);
    case Over::Shape: return label("shape", i, model.shape_name[i]);
    case Over::Actuator: return label("actuator", i, model.actuator_name[i]);
    case Over::World: return "world " + std::to_string(i);
    case Over::Dof: {
      const int j = dof_joint(model, i);
      return "dof " + std::to_string(i) + " of " + label("joint", j, model.joint_name[j]);
    }
  }
  return "";
}

// body i as it would be with x [width] as its parameter p (body_mass or body_inertia)
RigidBody entry_body(const Model& model, const Parameter& p, int i, const Scalar* x) {
  RigidBody body;
  body.mass = p.real == &Model::body_mass ? x[0] : model.body_mass[i];
  body.com = Eigen::Map<const Vec3>(&model.body_com[3 * i]);
  body.inertia = Eigen::Map<const Eigen::Matrix<Scalar, 3, 3, Eigen::RowMajor>>(
      p.real == &Model::body_inertia ? x : &model.body_inertia[9 * i]);
  return body;
}

// what is wrong with entry i's values x [width] of parameter p ("" where nothing is)
std::string value_problem(const Model& model, const Parameter& p, int i, const Scalar* x) {
  auto problem = [](const auto&... parts) {
    std::ostringstream os;
    os.precision(17);
    (os << ... << parts);
    return os.str();
  };
  for (int m = 0; m < p.width; ++m) {
    const Scalar v = x[m];
    if (p.check == Check::Integer) {
      if (!(std::isfinite(v) && v == std::trunc(v) && std::abs(v) < 1e9))
        return problem("must be a whole number, got ", v);
    } else if (p.check == Check::NotNegative) {
      if (!(v >= 0) || !std::isfinite(v)) return problem("the value must be finite and >= 0, got ", v);
    } else if (p.check == Check::Lower || p.check == Check::Upper) {
      const Scalar other = (model.*p.partner)[i];
      const Scalar lower = p.check == Check::Lower ? v : other, upper = p.check == Check::Lower ? other : v;
      if (std::isnan(lower) || std::isnan(upper) || lower > upper)
        return problem("the range must satisfy lower <= upper, got [", lower, ", ", upper, "]");
    } else if (p.check == Check::Finite) {
      if (!std::isfinite(v)) return problem("the value is not finite: ", v);
    }
  }
  if (p.check != Check::Body) return "";
  // a massless link (a frame between joints) stays massless: the collision filter walks through it
  return rigid_body_problem(entry_body(model, p, i, x), model.body_mass[i] == 0);
}

// whether the values [begin, end) all pass a check that looks at one value alone (false for the others: Body, Lower,
// Upper), in one run over them
bool values_fit(Check check, const Scalar* begin, const Scalar* end) {
  bool fit = true;
  switch (check) {
    case Check::Finite:
      for (const Scalar* x = begin; x < end; ++x) fit &= std::isfinite(*x);
      return fit;
    case Check::NotNegative:
      for (const Scalar* x = begin; x < end; ++x) fit &= *x >= 0 && std::isfinite(*x);
      return fit;
    case Check::Integer:
      for (const Scalar* x = begin; x < end; ++x)
        fit &= std::isfinite(*x) && *x == std::trunc(*x) && std::abs(*x) < 1e9;
      return fit;
    default: return false;
  }
}

// whether entry i's values x [width] of parameter p pass its check: value_problem's test without its message (the
// fast path of every value set_parameter checks)
bool value_fits(const Model& model, const Parameter& p, int i, const Scalar* x) {
  switch (p.check) {
    case Check::Finite:
    case Check::NotNegative:
    case Check::Integer: return values_fit(p.check, x, x + p.width);
    case Check::Lower:
    case Check::Upper: {
      const Scalar other = (model.*p.partner)[i];
      return p.check == Check::Lower ? x[0] <= other : other <= x[0];  // (false for a NaN)
    }
    case Check::Body: {
      // a positive mass fits a body whatever its inertia (a massless link's zero is value_problem's to judge)
      if (p.real == &Model::body_mass && x[0] > 0 && std::isfinite(x[0]) && model.body_mass[i] > 0) return true;
      return rigid_body_clearly_fine(entry_body(model, p, i, x)) || value_problem(model, p, i, x).empty();
    }
  }
  return false;
}

}  // namespace

struct ParameterIndex {
  WorldEntries of[static_cast<int>(Over::World) + 1];  // by Over
};

namespace {

const WorldEntries& world_entries(const Model& model, Over over) {
  if (!model.parameter_index) fail("set_parameter: the model is not finalized (its parameters are not indexed)");
  return model.parameter_index->of[static_cast<int>(over)];
}

}  // namespace

void Model::index_parameters() {
  auto index = std::make_shared<ParameterIndex>();
  for (const Over over : {Over::Body, Over::Dof, Over::Shape, Over::Actuator, Over::World})
    index->of[static_cast<int>(over)] = WorldEntries(*this, over);
  parameter_index = std::move(index);
}

const std::vector<std::string>& Model::parameter_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> out;
    for (const Parameter& p : kParameters) out.emplace_back(p.name);
    return out;
  }();
  return names;
}

std::span<const int> Model::parameter_entries(const std::string& field, int w) const {
  const Parameter& p = parameter(field);
  check_world(*this, field, w);
  const WorldEntries& by_world = world_entries(*this, p.over);
  return {by_world.entries.data() + by_world.start[w], by_world.entries.data() + by_world.start[w + 1]};
}

void Model::copy_parameters(const Model& other) {
  for (const Parameter& p : kParameters) {
    if (p.whole)
      this->*p.whole = other.*p.whole;
    else
      this->*p.real = other.*p.real;
  }
}

void Model::set_parameter(const std::string& field, const std::vector<int>& worlds, const Scalar* values,
                          size_t count) {
  const Parameter& p = parameter(field);
  for (const int w : worlds) check_world(*this, field, w);

  const WorldEntries& by_world = world_entries(*this, p.over);
  const std::vector<int>& start = by_world.start;
  const std::vector<int>& entries = by_world.entries;
  size_t expected = 0;
  for (const int w : worlds) expected += static_cast<size_t>(start[w + 1] - start[w]) * p.width;
  if (count != expected)
    fail("set_parameter ", field, ": ", count, " values for ", worlds.size(), " worlds, expected ", expected,
         " (each world's ", over_name(p.over), " times ", p.width, ")");

  // where each listed world's values begin
  std::vector<size_t> first(worlds.size() + 1, 0);
  for (size_t n = 0; n < worlds.size(); ++n)
    first[n + 1] = first[n] + static_cast<size_t>(start[worlds[n] + 1] - start[worlds[n]]) * p.width;
  const int listed = static_cast<int>(worlds.size());
  // check every value before writing any, the worlds on OpenMP's threads: the first bad entry in the order given is
  // named
  std::int64_t bad = -1;  // the list position of the first bad world
  std::vector<std::string> problems(worlds.size());
#pragma omp parallel for schedule(static)
  for (int n = 0; n < listed; ++n) {
    const int w = worlds[n];
    // the simple checks over the world's values in one run; an entry's own check where one fails or needs more
    if (values_fit(p.check, values + first[n], values + first[n + 1])) continue;
    size_t k = first[n];
    for (int e = start[w]; e < start[w + 1]; ++e, k += p.width) {
      if (value_fits(*this, p, entries[e], values + k)) continue;
      problems[n] = entry_label(*this, p.over, entries[e]) + ": " + value_problem(*this, p, entries[e], values + k);
      break;
    }
  }
  for (int n = 0; n < listed && bad < 0; ++n)
    if (!problems[n].empty()) bad = n;
  if (bad >= 0) fail("set_parameter ", field, ": world ", worlds[bad], ", ", problems[bad]);

  Scalar* real = p.real ? (this->*p.real).data() : nullptr;
  int* whole = p.whole ? (this->*p.whole).data() : nullptr;
#pragma omp parallel for schedule(static)
  for (int n = 0; n < listed; ++n) {
    const int w = worlds[n];
    const int count = start[w + 1] - start[w];
    if (count == 0) continue;
    // a world's entries one run of the field (a replicated world's): its values copied at once
    if (entries[start[w + 1] - 1] - entries[start[w]] == count - 1) {
      const size_t at = static_cast<size_t>(entries[start[w]]) * p.width;
      if (real)
        std::copy(values + first[n], values + first[n + 1], real + at);
      else
        std::transform(values + first[n], values + first[n + 1], whole + at,
                       [](Scalar x) { return static_cast<int>(x); });
      continue;
    }
    const Scalar* x = values + first[n];
    for (int e = start[w]; e < start[w + 1]; ++e, x += p.width) {
      const size_t at = static_cast<size_t>(entries[e]) * p.width;
      for (int m = 0; m < p.width; ++m) {
        if (real)
          real[at + m] = x[m];
        else
          whole[at + m] = static_cast<int>(x[m]);
      }
    }
  }
  ++parameter_writes;
  for (const int w : worlds) world_parameter_write[w] = parameter_writes;
}

}  // namespace novaphy
