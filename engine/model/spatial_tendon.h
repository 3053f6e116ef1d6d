// A spatial tendon (model.h, MuJoCo's <spatial>): a path through sites riding on bodies, wrapping around spheres and
// cylinders, halved (or more) after a pulley. Its length and its straight pieces at the bodies' poses, written once
// for the step's rows and forces, the sensors and the evaluations. A force f along the tendon pulls each straight
// piece's ends towards each other with f / divisor: the generalised force J^T f of its length's Jacobian (MuJoCo's
// mj_tendon, where a wrap's arc rides on the wrapped body and adds length but no Jacobian).
#pragma once

#include <vector>

#include "engine/model/model.h"

namespace novaphy {

// one straight piece of the path, in the world: from point[0] riding on body[0] to point[1] riding on body[1] (-1:
// the world), `unit` its direction (point[1] - point[0], normalised; zero where the points meet) and `scale` the
// pulleys' 1 / divisor
struct TendonSpan {
  int body[2];
  Vec3 point[2];
  Vec3 unit;
  Scalar scale;
};

// whether tendon t is spatial (a path) rather than fixed (joints)
inline bool is_spatial(const Model& model, int t) {
  return model.tendon_path_start[t] != model.tendon_path_start[t + 1];
}

// the world frame of body b in a pose table (body_q, 7 per body) for b >= 0, the identity for the world
inline Transform pose_in(const Scalar* body_q, int b) {
  return b < 0 ? Transform::identity() : Transform::from_array(body_q + 7 * static_cast<size_t>(b));
}

// spatial tendon t's length with its bodies at the poses body_q ([p, q] per body, the world frame), its straight
// pieces into spans (replaced)
Scalar spatial_tendon(const Model& model, int t, const Scalar* body_q, std::vector<TendonSpan>& spans);

// the tendon's velocity: each piece's ends' relative velocity along it, with body_qd ([velocity of the centre of
// mass; angular velocity] per body, the world frame) and body_q as spatial_tendon's
Scalar spatial_tendon_velocity(const Model& model, const std::vector<TendonSpan>& spans, const Scalar* body_q,
                               const Scalar* body_qd);

// body_f ([force through the centre of mass; torque] per body) += the wrenches of a force f along the tendon
void add_spatial_tendon_force(const Model& model, const std::vector<TendonSpan>& spans, const Scalar* body_q, Scalar f,
                              Scalar* body_f);

// each spatial tendon's rest length left NaN (TendonOptions: its length at joint_q0) set to that length: a step of
// finalize, once the bodies are laid out
void set_spatial_rest_lengths(Model& model);

// MuJoCo's wrap of a straight piece from x0 to x1 around a sphere or cylinder (type; radius r, its frame `geom` in the
// world, a cylinder's axis its z) on the side of the point `side` (null: the shorter way): the arc's length and its
// ends w0, w1 (world), or -1 where the piece does not wrap
Scalar wrap_around(TendonPathKind type, const Transform& geom, Scalar r, const Vec3& x0, const Vec3& x1,
                   const Vec3* side, Vec3& w0, Vec3& w1);

}  // namespace novaphy
