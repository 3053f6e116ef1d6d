// The builder's shapes: primitives, planes and convex meshes (their hulls, kernels/hull.h), and their tables in
// the Model.
#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <numeric>

#include "engine/model/builder.h"
#include "engine/model/builder_checks.h"
#include "engine/model/error.h"

namespace novaphy {

void ModelBuilder::set_impratio(Scalar impratio) {
  if (!(impratio > 0 && std::isfinite(impratio))) fail("impratio must be finite and > 0, got ", impratio);
  impratio_ = impratio;
}

void ModelBuilder::set_fluid(Scalar density, Scalar viscosity, const Vec3& wind) {
  check_nonnegative("set_fluid", "density", density);
  check_nonnegative("set_fluid", "viscosity", viscosity);
  check_finite("set_fluid", "wind", wind);
  fluid_density_ = density, fluid_viscosity_ = viscosity, wind_ = wind;
}

namespace {

// Tuckerman's coefficient of an ellipsoid of semi-axes (a, b, c) along a: the integral over l in [0, inf) of
// a b c / sqrt((a^2 + l)^3 (b^2 + l) (c^2 + l)), with l = s^2 w^2 / (1 - w)^2 (s the semi-axes' geometric mean) on
// w in [0, 1), by adaptive Simpson
Scalar tuckerman_kappa(Scalar a, Scalar b, Scalar c) {
  const Scalar s2 = std::cbrt(a * b * c) * std::cbrt(a * b * c);
  auto f = [&](Scalar w) {
    if (w >= 1) return Scalar(0);
    const Scalar l = s2 * w * w / ((1 - w) * (1 - w)), dl = s2 * 2 * w / ((1 - w) * (1 - w) * (1 - w));
    return a * b * c / std::sqrt((a * a + l) * (a * a + l) * (a * a + l) * (b * b + l) * (c * c + l)) * dl;
  };
  auto simpson = [&](auto&& self, Scalar x0, Scalar x1, Scalar f0, Scalar fm, Scalar f1, Scalar whole,
                     int depth) -> Scalar {
    const Scalar m = (x0 + x1) / 2, fl = f((x0 + m) / 2), fr = f((m + x1) / 2);
    const Scalar left = (m - x0) / 6 * (f0 + 4 * fl + fm), right = (x1 - m) / 6 * (fm + 4 * fr + f1);
    if (depth <= 0 || std::abs(left + right - whole) < 1e-13) return left + right + (left + right - whole) / 15;
    return self(self, x0, m, f0, fl, fm, left, depth - 1) + self(self, m, x1, fm, fr, f1, right, depth - 1);
  };
  const Scalar f0 = f(0), fm = f(0.5), f1 = f(1);
  return simpson(simpson, 0, 1, f0, fm, f1, (f0 + 4 * fm + f1) / 6, 40);
}

}  // namespace

int ModelBuilder::add_fluid_ellipsoid(int body, const Transform& frame, const Vec3& semi_axes,
                                      const FluidEllipsoidOptions& options) {
  const std::string item = "fluid ellipsoid " + std::to_string(fluid_ellipsoids_.size());
  if (body < 0 || body >= body_count()) fail(item, ": body index ", body, " out of range [0, ", body_count(), ")");
  const Transform placed = checked_transform(item, "frame", frame);
  for (int k = 0; k < 3; ++k) check_positive(item, "semi-axis", semi_axes[k]);
  for (const Scalar x :
       {options.blunt_drag, options.slender_drag, options.angular_drag, options.kutta_lift, options.magnus_lift})
    check_finite(item, "coefficient", x);
  FluidEllipsoidOptions o = options;
  // the fluid's virtual mass and inertia per unit density (Tuckerman's, MuJoCo's formulas), where not given
  const Scalar x = semi_axes[0], y = semi_axes[1], z = semi_axes[2];
  const Vec3 kappa(tuckerman_kappa(x, y, z), tuckerman_kappa(y, z, x), tuckerman_kappa(z, x, y));
  const Scalar volume = 4.0 / 3.0 * M_PI * x * y * z;
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    const Scalar rj = semi_axes[j] * semi_axes[j], rk = semi_axes[k] * semi_axes[k];
    const Scalar inertia = (rj - rk) * (rj - rk) * std::abs(kappa[k] - kappa[j]) /
                           std::max(Scalar(1e-15), std::abs(2 * (rj - rk) + (rj + rk) * (kappa[j] - kappa[k])));
    if (std::isnan(o.added_mass[i])) o.added_mass[i] = volume * kappa[i] / (2 - kappa[i]);
    if (std::isnan(o.added_inertia[i])) o.added_inertia[i] = volume * inertia / 5;
  }
  for (int k = 0; k < 3; ++k) {
    check_nonnegative(item, "added mass", o.added_mass[k]);
    check_nonnegative(item, "added inertia", o.added_inertia[k]);
  }
  fluid_ellipsoids_.push_back({body, placed, semi_axes, o});
  return static_cast<int>(fluid_ellipsoids_.size()) - 1;
}

void ModelBuilder::lay_out_fluid_ellipsoids(Model& model) const {
  model.fluid_ellipsoid_count = static_cast<int>(fluid_ellipsoids_.size());
  model.fluid_ellipsoid_body.clear();
  // by body (a body's ellipsoids together: Model::fluid_ellipsoid_body ascending), in the order added within one
  std::vector<int> order(fluid_ellipsoids_.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return fluid_ellipsoids_[a].body < fluid_ellipsoids_[b].body; });
  for (const int k : order) {
    const FluidEllipsoidRecord& e = fluid_ellipsoids_[k];
    const FluidEllipsoidOptions& o = e.options;
    auto put = [](std::vector<Scalar>& field, std::initializer_list<Scalar> values) {
      field.insert(field.end(), values.begin(), values.end());
    };
    model.fluid_ellipsoid_body.push_back(e.body);
    model.fluid_ellipsoid_frame.resize(model.fluid_ellipsoid_frame.size() + 7);
    e.frame.to_array(&model.fluid_ellipsoid_frame[model.fluid_ellipsoid_frame.size() - 7]);
    put(model.fluid_ellipsoid_size, {e.semi_axes[0], e.semi_axes[1], e.semi_axes[2]});
    put(model.fluid_ellipsoid_drag, {o.blunt_drag, o.slender_drag, o.angular_drag});
    put(model.fluid_ellipsoid_lift, {o.kutta_lift, o.magnus_lift});
    put(model.fluid_ellipsoid_added_mass, {o.added_mass[0], o.added_mass[1], o.added_mass[2]});
    put(model.fluid_ellipsoid_added_inertia, {o.added_inertia[0], o.added_inertia[1], o.added_inertia[2]});
  }
}

int ModelBuilder::add_shape(ShapeType type, int body, const Vec3& scale, const ShapeOptions& options, int mesh) {
  const std::string item = label("shape", shape_count(), options.name) + " (" + shape_type_name(type) + ")";
  if (body < -1 || body >= body_count()) fail(item, ": body index ", body, " out of range [-1, ", body_count(), ")");
  if (type != ShapeType::Plane)
    for (int k = 0; k < 3; ++k) check_positive(item, "size", scale[k]);
  check_nonnegative(item, "mu", options.mu);
  check_nonnegative(item, "mu_torsion", options.mu_torsion);
  check_nonnegative(item, "mu_rolling", options.mu_rolling);
  if (options.condim != 1 && options.condim != 3 && options.condim != 4 && options.condim != 6)
    fail(item, ": condim must be 1, 3, 4 or 6, got ", options.condim);
  if (!(options.restitution >= 0 && options.restitution <= 1))
    fail(item, ": restitution must be in [0, 1], got ", options.restitution);
  check_softness(item, options);
  ShapeRecord shape{type, body, scale, options, mesh};
  shape.options.xform = checked_transform(item, "xform", options.xform);
  shapes_.push_back(shape);
  shape_world_.push_back(body < 0 ? -1 : body_world_[body]);
  return shape_count() - 1;
}

int ModelBuilder::add_plane(const Vec3& normal, Scalar offset, const ShapeOptions& options) {
  check_finite("plane", "normal", normal);
  check_finite("plane", "offset", offset);
  if (normal.norm() < 1e-9) fail("plane: normal has zero length");
  const Vec3 n = normal.normalized();
  // plane shapes are the local XZ plane, normal +Y
  ShapeOptions plane = options;
  plane.xform.q = Quat::FromTwoVectors(Vec3::UnitY(), n);
  plane.xform.p = offset * n;
  return add_shape(ShapeType::Plane, -1, Vec3::Ones(), plane);
}

int ModelBuilder::add_ground_plane(Scalar y, const ShapeOptions& options) {
  return add_plane(Vec3::UnitY(), y, options);
}

int ModelBuilder::add_shape_box(int body, const Vec3& half_extents, const ShapeOptions& options) {
  return add_shape(ShapeType::Box, body, half_extents, options);
}

int ModelBuilder::add_shape_sphere(int body, Scalar radius, const ShapeOptions& options) {
  return add_shape(ShapeType::Sphere, body, Vec3::Constant(radius), options);
}

int ModelBuilder::add_shape_capsule(int body, Scalar radius, Scalar half_height, const ShapeOptions& options) {
  return add_shape(ShapeType::Capsule, body, Vec3(radius, half_height, radius), options);
}

int ModelBuilder::add_shape_cylinder(int body, Scalar radius, Scalar half_height, const ShapeOptions& options) {
  return add_shape(ShapeType::Cylinder, body, Vec3(radius, half_height, radius), options);
}

int ModelBuilder::add_shape_ellipsoid(int body, const Vec3& radii, const ShapeOptions& options) {
  return add_shape(ShapeType::Ellipsoid, body, radii, options);
}

int ModelBuilder::add_mesh(const std::vector<Vec3>& vertices, const std::string& name) {
  const std::string item = label("mesh", static_cast<int>(meshes_.size()), name);
  auto hull = std::make_shared<ConvexHull>();
  const std::string why = convex_hull(vertices, hull.get());
  if (!why.empty()) fail(item, ": ", why);
  // the hull centred on its vertices' mean (the shapes' frames move there), and its reach along each axis
  MeshRecord mesh{nullptr, Vec3::Zero(), Vec3::Zero()};
  for (const Vec3& v : hull->vertex) mesh.origin += v;
  mesh.origin /= static_cast<Scalar>(hull->vertex.size());
  for (Vec3& v : hull->vertex) v -= mesh.origin, mesh.reach = mesh.reach.cwiseMax(v.cwiseAbs());
  for (int f = 0; f < hull->face_count(); ++f) hull->face_offset[f] -= hull->face_normal[f].dot(mesh.origin);
  mesh.hull = std::move(hull);
  meshes_.push_back(std::move(mesh));
  return static_cast<int>(meshes_.size()) - 1;
}

int ModelBuilder::add_shape_mesh(int body, int mesh, const ShapeOptions& options) {
  if (mesh < 0 || mesh >= static_cast<int>(meshes_.size()))
    fail(label("shape", shape_count(), ""), " (Mesh): mesh index ", mesh, " out of range [0, ", meshes_.size(), ")");
  ShapeOptions placed = options;
  placed.xform = options.xform * Transform{meshes_[mesh].origin, Quat::Identity()};
  return add_shape(ShapeType::Mesh, body, meshes_[mesh].reach, placed, mesh);
}

void ModelBuilder::lay_out_shapes(Model& model) const {
  for (int s = 0; s < shape_count(); ++s) {
    const ShapeRecord& shape = shapes_[s];
    model.shape_type[s] = static_cast<int>(shape.type);
    model.shape_body[s] = shape.body;
    shape.options.xform.to_array(&model.shape_transform[7 * s]);
    Eigen::Map<Vec3>(&model.shape_scale[3 * s]) = shape.scale;
    model.shape_mu[s] = shape.options.mu;
    model.shape_mu_torsion[s] = shape.options.mu_torsion;
    model.shape_mu_rolling[s] = shape.options.mu_rolling;
    model.shape_restitution[s] = shape.options.restitution;
    model.shape_collision_group[s] = shape.options.collision_group;
    model.shape_collision_mask[s] = shape.options.collision_mask;
    model.shape_priority[s] = shape.options.priority;
    model.shape_condim[s] = shape.options.condim;
    std::copy(shape.options.solref.begin(), shape.options.solref.end(), &model.shape_solref[2 * s]);
    std::copy(shape.options.solimp.begin(), shape.options.solimp.end(), &model.shape_solimp[5 * s]);
    model.shape_solmix[s] = shape.options.solmix;
    model.shape_margin[s] = shape.options.margin;
    model.shape_gap[s] = shape.options.gap;
    model.shape_name.push_back(shape.options.name);
  }
}

void ModelBuilder::lay_out_meshes(Model& model) const {
  // the hulls the shapes use, each once (a replicated robot's shapes share theirs)
  std::map<const ConvexHull*, int> index;
  model.mesh_vertex_start = {0};
  model.mesh_face_start = {0};
  model.mesh_corner_start = {0};
  for (int s = 0; s < shape_count(); ++s) {
    model.shape_mesh[s] = -1;
    if (shapes_[s].mesh < 0) continue;
    const ConvexHull* hull = meshes_[shapes_[s].mesh].hull.get();
    const auto [it, added] = index.emplace(hull, static_cast<int>(index.size()));
    model.shape_mesh[s] = it->second;
    if (!added) continue;
    for (const Vec3& v : hull->vertex) model.mesh_vertex.insert(model.mesh_vertex.end(), {v.x(), v.y(), v.z()});
    for (int f = 0; f < hull->face_count(); ++f) {
      const Vec3& n = hull->face_normal[f];
      model.mesh_face_plane.insert(model.mesh_face_plane.end(), {n.x(), n.y(), n.z(), hull->face_offset[f]});
      for (int c = hull->corner_start[f]; c < hull->corner_start[f + 1]; ++c)
        model.mesh_corner.push_back(hull->corner[c]);
      model.mesh_corner_start.push_back(static_cast<int>(model.mesh_corner.size()));
    }
    model.mesh_vertex_start.push_back(static_cast<int>(model.mesh_vertex.size() / 3));
    model.mesh_face_start.push_back(static_cast<int>(model.mesh_face_plane.size() / 4));
  }
  model.mesh_count = static_cast<int>(index.size());
  model.mesh_vertex_count = model.mesh_vertex_start.back();
  model.mesh_face_count = model.mesh_face_start.back();
  model.mesh_corner_count = static_cast<int>(model.mesh_corner.size());
}

}  // namespace novaphy
