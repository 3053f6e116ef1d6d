#include "kernels/hull.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

extern "C" {
#include <libqhull_r/qhull_ra.h>
}

namespace novaphy {

namespace {

// a facet's vertices in counterclockwise order about its outward normal n
std::vector<int> ordered_corners(std::vector<int> corners, const std::vector<Vec3>& vertex, const Vec3& n) {
  Vec3 center = Vec3::Zero();
  for (int v : corners) center += vertex[v];
  center /= static_cast<Scalar>(corners.size());
  const Vec3 u = (vertex[corners[0]] - center).normalized(), w = n.cross(u);
  auto angle = [&](int v) { return std::atan2(w.dot(vertex[v] - center), u.dot(vertex[v] - center)); };
  std::sort(corners.begin(), corners.end(), [&](int a, int b) { return angle(a) < angle(b); });
  return corners;
}

// qhull's first line of complaint
std::string first_line(const std::string& text) {
  const size_t end = text.find('\n');
  return text.substr(0, end == std::string::npos ? text.size() : end);
}

}  // namespace

std::string convex_hull(const std::vector<Vec3>& points, ConvexHull* hull) {
  if (points.size() < 4) return "a hull needs at least 4 points, got " + std::to_string(points.size());
  for (size_t i = 0; i < points.size(); ++i)
    if (!points[i].allFinite()) return "point " + std::to_string(i) + " is not finite";
  std::vector<coordT> coords;
  for (const Vec3& p : points) coords.insert(coords.end(), {p.x(), p.y(), p.z()});
  char* text = nullptr;
  size_t text_size = 0;
  FILE* errors = open_memstream(&text, &text_size);
  qhT qh_storage;
  qhT* qh = &qh_storage;
  qh_zero(qh, errors);
  char options[] = "qhull Qs";
  const int status =
      qh_new_qhull(qh, 3, static_cast<int>(points.size()), coords.data(), False, options, nullptr, errors);
  std::string why;
  *hull = ConvexHull{};
  if (status != 0) {
    std::fflush(errors);
    why = "the points span no volume (all on one plane or line; qhull: " + first_line(text ? text : "") + ")";
  } else {
    std::map<int, int> index;  // qhull's point id -> hull vertex
    facetT* facet;
    FORALLfacets {
      const Vec3 n(facet->normal[0], facet->normal[1], facet->normal[2]);
      std::vector<int> corners;
      vertexT *vertex, **vertexp;
      FOREACHvertex_(facet->vertices) {
        const int id = qh_pointid(qh, vertex->point);
        const auto [it, added] = index.emplace(id, static_cast<int>(hull->vertex.size()));
        if (added) hull->vertex.push_back(points[id]);
        corners.push_back(it->second);
      }
      for (int v : ordered_corners(corners, hull->vertex, n)) hull->corner.push_back(v);
      hull->corner_start.push_back(static_cast<int>(hull->corner.size()));
      hull->face_normal.push_back(n);
      hull->face_offset.push_back(-facet->offset);
    }
  }
  qh_freeqhull(qh, !qh_ALL);
  int still_long, total_long;
  qh_memfreeshort(qh, &still_long, &total_long);
  std::fclose(errors);
  std::free(text);
  return why;
}

}  // namespace novaphy
