// The convex hull of a point set, computed by qhull (Barber, Dobkin and Huhdanpaa 1996, Debian's libqhull_r):
// the polyhedron a mesh collides as (MuJoCo collides every mesh as its hull too).
#pragma once

#include <string>
#include <vector>

#include "kernels/spatial.h"

namespace novaphy {

// vertices, and faces as polygons (coplanar triangles merged): face f's corners are the vertices
// corner[corner_start[f] .. corner_start[f + 1]), counterclockwise seen from outside; face_normal[f] is its
// outward unit normal and face_offset[f] = face_normal[f] . x for every x on the face
struct ConvexHull {
  std::vector<Vec3> vertex;
  std::vector<int> corner_start{0};
  std::vector<int> corner;
  std::vector<Vec3> face_normal;
  std::vector<Scalar> face_offset;
  int face_count() const { return static_cast<int>(face_normal.size()); }
};

// the hull of `points` into *hull; returns "" or why there is none: fewer than 4 points, a point not finite,
// or all of them on one plane or line (qhull's reason follows)
std::string convex_hull(const std::vector<Vec3>& points, ConvexHull* hull);

}  // namespace novaphy
