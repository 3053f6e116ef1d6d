#include "test_support.h"

#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>

namespace novaphy::test {

namespace {

Scalar uniform(std::mt19937& rng, Scalar lo, Scalar hi) { return std::uniform_real_distribution<Scalar>(lo, hi)(rng); }
int uniform_int(std::mt19937& rng, int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); }

Vec3 random_vec(std::mt19937& rng, Scalar r) {
  return Vec3(uniform(rng, -r, r), uniform(rng, -r, r), uniform(rng, -r, r));
}

Quat random_quat(std::mt19937& rng) {
  std::normal_distribution<Scalar> n;
  return Quat(n(rng), n(rng), n(rng), n(rng)).normalized();
}

Transform random_transform(std::mt19937& rng, Scalar r) {
  Transform T;
  T.p = random_vec(rng, r);
  T.q = random_quat(rng);
  return T;
}

// principal moments that satisfy the triangle inequality, in a random orientation
Mat3 random_inertia(std::mt19937& rng, Quat* orientation = nullptr, Vec3* moments = nullptr) {
  const Scalar a = uniform(rng, 0.02, 0.3), b = uniform(rng, 0.02, 0.3);
  const Scalar c = uniform(rng, std::abs(a - b) + 0.01, a + b - 0.01);
  const Quat q = random_quat(rng);
  const Mat3 R = q.toRotationMatrix();
  if (orientation) *orientation = q;
  if (moments) *moments = Vec3(a, b, c);
  return R * Vec3(a, b, c).asDiagonal() * R.transpose();
}

std::string fmt(const Vec3& v) {
  std::ostringstream os;
  os.precision(17);
  os << v.x() << " " << v.y() << " " << v.z();
  return os.str();
}

}  // namespace

Scalar relative_error(const MatX& a, const MatX& b) {
  if (b.size() == 0) return a.size() == 0 ? 0 : std::numeric_limits<Scalar>::infinity();
  return (a - b).cwiseAbs().maxCoeff() / std::max<Scalar>(1, b.cwiseAbs().maxCoeff());
}

void randomize_state(const Model& model, State& state, std::mt19937& rng, bool wrenches) {
  for (int j = 0; j < model.joint_count; ++j) {
    Scalar* q = state.joint_q.data() + model.joint_q_start[j];  // past the end for a Fixed joint
    const auto type = static_cast<JointType>(model.joint_type[j]);
    if (type == JointType::Revolute) q[0] = uniform(rng, -M_PI, M_PI);
    if (type == JointType::Prismatic) q[0] = uniform(rng, -0.5, 0.5);
    if (type == JointType::Ball) Eigen::Map<Eigen::Vector4d>{q} = random_quat(rng).coeffs();
    if (type == JointType::Free) random_transform(rng, 1.0).to_array(q);
  }
  for (Scalar& v : state.joint_qd) v = uniform(rng, -2, 2);
  for (Scalar& f : state.body_f) f = wrenches ? uniform(rng, -3, 3) : 0;
}

State run_steps(const Model& model, const Control& control, int steps, Scalar dt,
                const SolverFeatherstoneSettings& settings) {
  SolverFeatherstone solver(model, settings);
  CollisionPipeline pipeline(model);
  Contacts contacts = pipeline.contacts();
  State state = model.state();
  for (int k = 0; k < steps; ++k) {
    pipeline.collide(state, contacts);
    solver.step(state, state, control, contacts, dt);
  }
  return state;
}

Model random_builder_tree(std::mt19937& rng, int links, int roots) {
  ModelBuilder builder(random_vec(rng, 10));
  for (int r = 0; r < roots; ++r) {
    const int first = builder.body_count();
    for (int i = 0; i < links; ++i) {
      RigidBody body;
      body.mass = uniform(rng, 0.2, 3);
      body.com = random_vec(rng, 0.3);
      body.inertia = random_inertia(rng);
      const int child = builder.add_body(body, random_transform(rng, 1));
      const int parent = i == 0 ? -1 : first + uniform_int(rng, 0, i - 1);
      JointType type = static_cast<JointType>(uniform_int(rng, 0, i == 0 ? 4 : 3));
      JointOptions options;
      options.parent_xform = random_transform(rng, 0.5);
      options.child_xform = random_transform(rng, 0.5);
      options.dof.axis = random_vec(rng, 1);
      options.dof.armature = uniform(rng, 0, 0.1);
      options.dof.damping = uniform(rng, 0, 0.5);
      options.dof.stiffness = uniform(rng, 0, 2);
      options.dof.q_ref = uniform(rng, -0.5, 0.5);
      builder.add_joint(type, parent, child, options);
    }
  }
  return builder.finalize();
}

std::string random_tree_mjcf(std::mt19937& rng, int bodies, bool floating) {
  std::vector<int> parent(bodies);
  std::vector<std::vector<int>> children(bodies);
  std::vector<int> roots;
  for (int i = 0; i < bodies; ++i) {
    parent[i] = (i == 0 || (!floating && uniform(rng, 0, 1) < 0.1)) ? -1 : uniform_int(rng, 0, i - 1);
    (parent[i] < 0 ? roots : children[parent[i]]).push_back(i);
  }

  std::ostringstream xml;
  xml.precision(17);
  xml << "<mujoco model=\"random_tree\">\n  <option gravity=\"" << fmt(random_vec(rng, 10)) << "\"/>\n  <worldbody>\n";
  std::function<void(int, int)> write = [&](int b, int depth) {
    const std::string ind(2 * depth, ' ');
    const Quat bq = random_quat(rng);
    xml << ind << "<body name=\"b" << b << "\" pos=\"" << fmt(random_vec(rng, 0.5)) << "\" quat=\"" << bq.w() << " "
        << bq.x() << " " << bq.y() << " " << bq.z() << "\">\n";
    if (floating && parent[b] < 0) {
      xml << ind << "  <freejoint name=\"j" << b << "_free\"/>\n";
    } else {
      // MuJoCo allows a ball joint only as the last rotation of a body
      const int joints = uniform_int(rng, parent[b] < 0 ? 1 : 0, 3);
      for (int k = 0, type = -1; k < joints && type != 2; ++k) {
        type = uniform_int(rng, 0, 2);
        xml << ind << "  <joint name=\"j" << b << "_" << k << "\" type=\""
            << (type == 0   ? "hinge"
                : type == 1 ? "slide"
                            : "ball")
            << "\" pos=\"" << fmt(random_vec(rng, 0.3)) << "\" armature=\"" << uniform(rng, 0, 0.1) << "\" damping=\""
            << uniform(rng, 0, 0.5) << "\"";
        if (type != 2)
          xml << " axis=\"" << fmt(random_vec(rng, 1)) << "\" stiffness=\"" << uniform(rng, 0, 2) << "\" springref=\""
              << uniform(rng, -0.5, 0.5) << "\" ref=\"" << uniform(rng, -0.5, 0.5) << "\"";
        xml << "/>\n";
      }
    }
    const Mat3 I = random_inertia(rng);
    xml << ind << "  <inertial pos=\"" << fmt(random_vec(rng, 0.3)) << "\" mass=\"" << uniform(rng, 0.2, 3)
        << "\" fullinertia=\"" << I(0, 0) << " " << I(1, 1) << " " << I(2, 2) << " " << I(0, 1) << " " << I(0, 2) << " "
        << I(1, 2) << "\"/>\n";
    for (const int c : children[b]) write(c, depth + 1);
    xml << ind << "</body>\n";
  };
  for (const int r : roots) write(r, 2);
  xml << "  </worldbody>\n</mujoco>\n";
  return xml.str();
}

std::string write_temp_file(const std::string& name, const std::string& text) {
  const auto path =
      std::filesystem::temp_directory_path() / ("novaphy_test_" + std::to_string(::getpid()) + "_" + name);
  std::ofstream(path) << text;
  return path.string();
}

HullArrays::HullArrays(const std::vector<Vec3>& points) {
  const std::string why = convex_hull(points, &hull);
  if (!why.empty()) throw std::invalid_argument("HullArrays: " + why);
  for (int f = 0; f < hull.face_count(); ++f)
    planes.insert(planes.end(),
                  {hull.face_normal[f].x(), hull.face_normal[f].y(), hull.face_normal[f].z(), hull.face_offset[f]});
  // (Vec3 is packed: three numbers a vertex)
  view = {hull.vertex[0].data(), static_cast<int>(hull.vertex.size()),
          planes.data(),         hull.corner_start.data(),
          hull.corner.data(),    hull.face_count()};
}

std::vector<Vec3> prism_points(int n, Scalar r, Scalar h) {
  std::vector<Vec3> points;
  for (int k = 0; k < n; ++k)
    for (const Scalar y : {-h, h})
      points.push_back(Vec3(r * std::cos(2 * M_PI * k / n), y, r * std::sin(2 * M_PI * k / n)));
  return points;
}

}  // namespace novaphy::test
