// The broad phase of CollisionPipeline (engine/collision/pipeline.h) at each collide: shapes' bounds, sweep and
// prune in a world of many shapes, and worlds alike a group at a time in lanes (a world per lane, as WorldGroups
// grouped them): their boxes, their pairs' overlaps and their planes' reach.
#include <algorithm>

#include "engine/collision/pipeline.h"
#include "kernels/collide.h"
#include "kernels/lane_transpose.h"

namespace novaphy {

namespace {

constexpr Scalar kIdentity[7] = {0, 0, 0, 0, 0, 0, 1};  // where a shape on no body has its "body"

BoundsKind bounds_kind(int type) {
  switch (static_cast<ShapeType>(type)) {
    case ShapeType::Sphere: return BoundsKind::Sphere;
    case ShapeType::Box: return BoundsKind::Box;
    case ShapeType::Capsule: return BoundsKind::Capsule;
    // (a cylinder, an ellipsoid and a mesh's hull lie within the box of their scale)
    case ShapeType::Cylinder:
    case ShapeType::Ellipsoid:
    case ShapeType::Mesh: return BoundsKind::Box;
    case ShapeType::Plane: break;
  }
  return BoundsKind::Plane;
}

}  // namespace

CollisionPipeline::Box CollisionPipeline::box(const State& state, int s) const {
  const int b = model_.shape_body[s];
  Scalar pose[7];
  Vec3 lower, upper;
  shape_bounds(bounds_kind(model_.shape_type[s]), b < 0 ? kIdentity : &state.body_q[7 * b],
               &model_.shape_transform[7 * s], &model_.shape_scale[3 * s], reach_, pose, lower.data(), upper.data());
  return {Transform::from_array(pose), lower, upper};
}

void CollisionPipeline::sweep_world(int w, const std::vector<Box>& boxes, std::vector<Found>& out) {
  const std::vector<int>& shapes = shapes_.world_others[w];
  const int n = static_cast<int>(shapes.size());
  std::vector<int>& order = world_sweep_[w];  // local indices
  std::sort(order.begin(), order.end(), [&](int x, int y) {
    return boxes[x].lower.x() < boxes[y].lower.x() || (boxes[x].lower.x() == boxes[y].lower.x() && x < y);
  });
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n && boxes[order[j]].lower.x() <= boxes[order[i]].upper.x(); ++j)
      test_pair(shapes[order[i]], boxes[order[i]], shapes[order[j]], boxes[order[j]], out, shapes[order[i]],
                shapes[order[j]]);
}

void CollisionPipeline::group_boxes(const State& state, int g, Scratch& scratch) const {
  using V = Lanes<Scalar>;
  constexpr int L = kLanes<Scalar>;
  const int first = groups_.first[g], count = groups_.first[g + 1] - first;
  const int n = static_cast<int>(shapes_.world_others[first].size());
  const int* group_body = groups_.body.data() + groups_.body_start[g];
  scratch.lanes.resize(n);
  // the lanes' runs of bodies moved into lanes at once (a tiled transpose), where the group has them
  const WorldGroups::BodyRun& run = groups_.run[g];
  const int* place = run.length > 0 ? &groups_.run_place[groups_.body_start[g] / L] : nullptr;
  if (run.length > 0) {
    const Scalar* rows[L];
    for (int l = 0; l < L; ++l) rows[l] = &state.body_q[7 * run.first[l]];
    scratch.body_q.resize(7 * run.length);
    lanes_from_rows<Scalar>(rows, 7 * run.length, scratch.body_q.data());
  }
  const std::vector<int>& read = shapes_.world_others[groups_.read_world[g]];
  for (int i = 0; i < n; ++i) {
    // shape i of each world
    V gathered[7], local[7], scale[3];
    const V* body = gathered;
    if (place && place[i] >= 0) {
      body = &scratch.body_q[7 * place[i]];
    } else {
      for (int l = 0; l < L; ++l) {
        const int b = group_body[L * i + l];
        const Scalar* x = b < 0 ? kIdentity : &state.body_q[7 * b];
        for (int k = 0; k < 7; ++k) gathered[k][l] = x[k];
      }
    }
    const bool same = groups_.same[g] >> i & 1;
    if (same) {
      const int s = read[i];
      for (int k = 0; k < 7; ++k) local[k] = V{} + model_.shape_transform[7 * s + k];
      for (int k = 0; k < 3; ++k) scale[k] = V{} + model_.shape_scale[3 * s + k];
    } else {
      for (int l = 0; l < L; ++l) {
        const int s = shapes_.world_others[first + (l < count ? l : 0)][i];
        for (int k = 0; k < 7; ++k) local[k][l] = model_.shape_transform[7 * s + k];
        for (int k = 0; k < 3; ++k) scale[k][l] = model_.shape_scale[3 * s + k];
      }
    }
    ShapeLanes& X = scratch.lanes[i];
    shape_bounds(bounds_kind(model_.shape_type[same ? read[i] : shapes_.world_others[first][i]]), body, local, scale,
                 reach_, X.pose, X.lower, X.upper);
  }
  // the slots' boxes, each joining its shapes'
  const int slot_start = groups_.slot_start[g], slots = groups_.slot_start[g + 1] - slot_start;
  const std::uint64_t* slot_shapes = groups_.slot_shapes.data() + slot_start;
  const std::uint64_t* slot_pairs = groups_.slot_pairs.data() + slot_start;
  scratch.slots.resize(slots);
  for (int u = 0; u < slots; ++u) {
    ShapeLanes& U = scratch.slots[u];
    std::uint64_t m = slot_shapes[u];
    const ShapeLanes& X = scratch.lanes[__builtin_ctzll(m)];
    std::copy(X.lower, X.lower + 3, U.lower);
    std::copy(X.upper, X.upper + 3, U.upper);
    for (m &= m - 1; m != 0; m &= m - 1) {
      const ShapeLanes& Y = scratch.lanes[__builtin_ctzll(m)];
      for (int k = 0; k < 3; ++k) {
        U.lower[k] = Y.lower[k] < U.lower[k] ? Y.lower[k] : U.lower[k];
        U.upper[k] = Y.upper[k] > U.upper[k] ? Y.upper[k] : U.upper[k];
      }
    }
  }
  // the pairs the masks allow whose boxes overlap, tested in every world at once, where their slots' boxes
  // overlap in some world
  scratch.hits.assign(static_cast<size_t>(L) * n, 0);
  const std::uint64_t* mask = shapes_.world_pairs.data() + shapes_.world_pair_start[first];
  for (int u = 0; u < slots; ++u) {
    const ShapeLanes& U = scratch.slots[u];
    for (std::uint64_t pairs = slot_pairs[u]; pairs != 0; pairs &= pairs - 1) {
      const int v = __builtin_ctzll(pairs);
      const ShapeLanes& W = scratch.slots[v];
      if (!any_lane<Scalar>(boxes_overlap(U.lower, U.upper, W.lower, W.upper))) continue;
      for (std::uint64_t shapes = slot_shapes[u]; shapes != 0; shapes &= shapes - 1) {
        const int i = __builtin_ctzll(shapes);
        const ShapeLanes& A = scratch.lanes[i];
        for (std::uint64_t m = mask[i] & slot_shapes[v]; m != 0; m &= m - 1) {
          const int j = __builtin_ctzll(m);
          const ShapeLanes& B = scratch.lanes[j];
          const IntLanes<Scalar> hit = boxes_overlap(A.lower, A.upper, B.lower, B.upper);
          if (!any_lane<Scalar>(hit)) continue;
          for (int l = 0; l < count; ++l)
            if (hit[l]) scratch.hits[l * n + i] |= std::uint64_t{1} << j;
        }
      }
    }
  }
}

void CollisionPipeline::group_planes(int g, Scratch& scratch) const {
  using V = Lanes<Scalar>;
  constexpr int L = kLanes<Scalar>;
  const int first = groups_.first[g], count = groups_.first[g + 1] - first;
  const int start = groups_.plane_start[g], planes = groups_.plane_start[g + 1] - start;
  const std::vector<int>&first_shapes = shapes_.world_others[first],
        &read = shapes_.world_others[groups_.read_world[g]];
  const int n = static_cast<int>(first_shapes.size());
  scratch.plane_hits.assign(static_cast<size_t>(L) * planes, 0);
  scratch.plane_spheres.resize(static_cast<size_t>(planes) * n);
  scratch.spheres = 0;
  for (int i = 0; i < n; ++i) {
    const int s = groups_.same[g] >> i & 1 ? read[i] : first_shapes[i];
    if (model_.shape_type[s] == static_cast<int>(ShapeType::Sphere)) scratch.spheres |= std::uint64_t{1} << i;
  }
  for (int k = 0; k < planes; ++k) {
    V origin[3], normal[3];
    const int *plane = &groups_.plane_lanes[(start + k) * L], read_p = groups_.plane_read[start + k];
    if (groups_.plane_still[start + k]) {
      for (int m = 0; m < 3; ++m)
        origin[m] = V{} + plane_pose_[read_p].p[m], normal[m] = V{} + plane_normal_[read_p][m];
    } else {
      for (int l = 0; l < L; ++l)
        for (int m = 0; m < 3; ++m)
          origin[m][l] = plane_pose_[plane[l]].p[m], normal[m][l] = plane_normal_[plane[l]][m];
    }
    for (std::uint64_t m = groups_.plane_shapes[start + k]; m != 0; m &= m - 1) {
      const int i = __builtin_ctzll(m);
      const ShapeLanes& X = scratch.lanes[i];
      const IntLanes<Scalar> hit = plane_box_distance(origin, normal, X.lower, X.upper) <= 0;
      if (!any_lane<Scalar>(hit)) continue;
      for (int l = 0; l < count; ++l)
        if (hit[l]) scratch.plane_hits[l * planes + k] |= std::uint64_t{1} << i;
      if (!(scratch.spheres >> i & 1)) continue;
      // the sphere's contacts in lanes, its radius and the pair's margin read once where alike in every world
      V radius, margin;
      const bool same = (groups_.same[g] >> i & 1) && read_p >= 0;
      for (int l = 0; l < L; ++l) {
        const int s = same ? read[i] : shapes_.world_others[first + (l < count ? l : 0)][i];
        radius[l] = l > 0 && same ? radius[0] : model_.shape_scale[3 * s];
        margin[l] = l > 0 && same ? margin[0] : pair_margin(same ? read_p : plane[l], s);
      }
      SphereOnPlane& c = scratch.plane_spheres[k * n + i];
      c.touching = plane_sphere_contact<V>(origin, normal, X.pose, radius, margin, c.point, &c.depth);
    }
  }
}

void CollisionPipeline::lane_boxes(int l, std::uint64_t needed, Scratch& scratch) const {
  const int n = static_cast<int>(scratch.lanes.size());
  if (static_cast<int>(scratch.boxes.size()) < n) scratch.boxes.resize(n);
  for (std::uint64_t m = needed; m != 0; m &= m - 1) {
    const int i = __builtin_ctzll(m);
    const ShapeLanes& X = scratch.lanes[i];
    Box& box = scratch.boxes[i];
    box.pose.p = Vec3(X.pose[0][l], X.pose[1][l], X.pose[2][l]);
    box.pose.q = Quat(X.pose[6][l], X.pose[3][l], X.pose[4][l], X.pose[5][l]);
    box.lower = Vec3(X.lower[0][l], X.lower[1][l], X.lower[2][l]);
    box.upper = Vec3(X.upper[0][l], X.upper[1][l], X.upper[2][l]);
  }
}

}  // namespace novaphy
