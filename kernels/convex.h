// The narrow phase of the convex shapes beyond the primitives of kernels/collide: cylinders, ellipsoids and
// convex hulls (kernels/hull), against each other and every primitive. A pair's deepest point, normal and
// depth come from libccd's Minkowski portal refinement (Snethen, Game Programming Gems 7; the method MuJoCo
// 2.2.2 collides meshes with), each shape grown by half the margin; where both shapes meet with a face or an
// edge (a box or hull face, a cylinder's cap or side, a capsule's side) the incident feature is clipped to
// the reference face (Sutherland-Hodgman), for a manifold of up to 4 points that rests. Planes meet the new
// shapes in closed form. Outputs as in kernels/collide.h (normal from a to b, depth > 0 overlapping).
#pragma once

#include "kernels/collide.h"

namespace novaphy {

// a hull's arrays (a view of the model's mesh_* fields): vertices [vertex_count][3] in the shape frame; face f's
// plane [f][4] (outward unit normal, offset) and corners corner[corner_start[f] .. corner_start[f + 1])
struct HullView {
  const Scalar* vertex = nullptr;
  int vertex_count = 0;
  const Scalar* face_plane = nullptr;
  const int* corner_start = nullptr;
  const int* corner = nullptr;
  int face_count = 0;
};

// a shape at its world pose. size: a sphere's radius; a box's half extents; a capsule's or cylinder's radius
// and half height (along local Y); an ellipsoid's semi-axes; a hull's is unused
enum class ConvexKind { Sphere, Box, Capsule, Cylinder, Ellipsoid, Hull };
struct ConvexShape {
  ConvexKind kind = ConvexKind::Sphere;
  Transform pose;
  Vec3 size = Vec3::Zero();
  const HullView* hull = nullptr;
};

// the point of s farthest along the world direction d (nonzero)
Vec3 convex_support(const ConvexShape& s, const Vec3& d);

// a and b (any kinds), up to 4 points
int collide_convex(const ConvexShape& a, const ConvexShape& b, Scalar margin, ContactPoint* out);

// a plane against a cylinder (each cap's deepest rim point and four fixed rim points, up to 4 kept), an
// ellipsoid (its deepest point) or a hull (its vertices within the margin, up to 4 kept)
int collide_plane_cylinder(const Transform& plane, const Transform& cylinder, Scalar radius, Scalar half_height,
                           Scalar margin, ContactPoint* out);
int collide_plane_ellipsoid(const Transform& plane, const Transform& ellipsoid, const Vec3& radii, Scalar margin,
                            ContactPoint* out);
int collide_plane_hull(const Transform& plane, const Transform& pose, const HullView& hull, Scalar margin,
                       ContactPoint* out);

}  // namespace novaphy
