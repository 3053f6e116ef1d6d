#include "engine/collision/world_groups.h"

#include <algorithm>

namespace novaphy {

namespace {

// the narrow phase reads the same of shapes s and a: type, size, mesh, margin and solref
bool narrow_alike(const Model& model, int s, int a) {
  bool same = model.shape_type[s] == model.shape_type[a] && model.shape_mesh[s] == model.shape_mesh[a] &&
              model.shape_margin[s] == model.shape_margin[a];
  for (int k = 0; k < 3; ++k) same &= model.shape_scale[3 * s + k] == model.shape_scale[3 * a + k];
  for (int k = 0; k < 2; ++k) same &= model.shape_solref[2 * s + k] == model.shape_solref[2 * a + k];
  return same;
}

// and so do the bounds (local pose, size): a group reads shapes alike so from another world
bool read_alike(const Model& model, int s, int a) {
  bool same = narrow_alike(model, s, a);
  for (int k = 0; k < 7; ++k) same &= model.shape_transform[7 * s + k] == model.shape_transform[7 * a + k];
  return same;
}

}  // namespace

WorldGroups::WorldGroups(const Model& model, const ShapeFilter& filter, const WorldShapes& shapes) {
  group_worlds(model, filter, shapes);
  describe_groups(model, filter, shapes);
}

void WorldGroups::group_worlds(const Model& model, const ShapeFilter& filter, const WorldShapes& shapes) {
  // consecutive worlds alike, up to kLanes<Scalar> of them, have their boxes, their pairs' overlaps and
  // their planes' reach found together, a world per lane
  const int world_count = model.world_count;
  for (int w = 0; w < world_count;) {
    int end = w + 1;
    while (end < world_count && end - w < kLanes<Scalar> && alike(model, filter, shapes, w, end)) ++end;
    first.push_back(w);
    w = end;
  }
  first.push_back(world_count);
}

bool WorldGroups::alike(const Model& model, const ShapeFilter& filter, const WorldShapes& shapes, int v, int w) {
  // both test their pairs by masks, the same masks, over shapes of the same types, each on a body or not;
  // they meet planes in the same order, each the same shapes
  const std::vector<int>&a = shapes.world_others[v], &b = shapes.world_others[w];
  const std::vector<int>& pair_start = shapes.world_pair_start;
  if (pair_start[v] < 0 || pair_start[w] < 0 || a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i)
    if (model.shape_type[a[i]] != model.shape_type[b[i]] ||
        (model.shape_body[a[i]] < 0) != (model.shape_body[b[i]] < 0) ||
        shapes.world_pairs[pair_start[v] + i] != shapes.world_pairs[pair_start[w] + i])
      return false;
  const std::vector<int> order = shapes.plane_order(v);
  if (order != shapes.plane_order(w)) return false;
  for (const int code : order)
    for (size_t i = 0; i < a.size(); ++i)
      if (filter.may_collide(shapes.plane_of(v, code), a[i]) != filter.may_collide(shapes.plane_of(w, code), b[i]))
        return false;
  return true;
}

void WorldGroups::describe_groups(const Model& model, const ShapeFilter& filter, const WorldShapes& shapes) {
  // per group of several: each shape's body in each lane, and which shapes are read once (a replicated robot's),
  // where group_boxes and the narrow phase read the model's arrays from one world only (a collide after a step
  // finds little of them in cache); the runs of bodies its lanes' shapes lie in, its planes (each the same in all
  // its worlds, or not) and its slots
  const int groups = count();
  body_start.assign(groups, -1);
  same.assign(groups, 0);
  read_world.assign(groups, -1);
  run.assign(groups, {});
  plane_start.assign(1, 0);
  slot_start.assign(1, 0);
  int last_read = -1;
  std::vector<int> read_planes;
  for (int g = 0; g < groups; ++g) {
    if (first[g + 1] - first[g] > 1) {
      group_shapes(model, shapes, g, last_read);
      last_read = read_world[g];
      group_runs(shapes, g);
      group_plane_reach(model, filter, shapes, g, read_planes);
      group_slots(shapes, g);
    }
    plane_start.push_back(static_cast<int>(plane_read.size()));
    slot_start.push_back(static_cast<int>(slot_shapes.size()));
  }
}

void WorldGroups::group_shapes(const Model& model, const WorldShapes& shapes, int g, int last_read) {
  const int L = kLanes<Scalar>;
  const int first_world = first[g], worlds = first[g + 1] - first_world;
  const std::vector<int>& first_shapes = shapes.world_others[first_world];
  const int n = static_cast<int>(first_shapes.size());
  body_start[g] = static_cast<int>(body.size());
  for (int i = 0; i < n; ++i) {
    bool alike_in_all = true;
    for (int l = 0; l < L; ++l) {
      const int s = shapes.world_others[first_world + (l < worlds ? l : 0)][i];
      body.push_back(model.shape_body[s]);
      alike_in_all &= read_alike(model, s, first_shapes[i]);
    }
    if (alike_in_all) same[g] |= std::uint64_t{1} << i;
  }
  read_world[g] = first_world;
  if (last_read < 0 || static_cast<int>(shapes.world_others[last_read].size()) != n) return;
  for (std::uint64_t m = same[g]; m != 0; m &= m - 1)
    if (!read_alike(model, shapes.world_others[last_read][__builtin_ctzll(m)], first_shapes[__builtin_ctzll(m)]))
      return;
  read_world[g] = last_read;
}

void WorldGroups::group_runs(const WorldShapes& shapes, int g) {
  // each lane's run starts at the lowest body its shapes sit on; a run serves when every lane's shapes
  // sit at the same places in it and it is at most twice as long as the shapes are many (otherwise, as
  // where a world's bodies lie among other worlds', its shapes' bodies are read number by number)
  constexpr int L = kLanes<Scalar>;
  const int n = static_cast<int>(shapes.world_others[first[g]].size());
  const int* shape_body = body.data() + body_start[g];
  BodyRun lanes_run;
  std::vector<int> place(n, -1);
  for (int l = 0; l < L; ++l) {
    lanes_run.first[l] = -1;
    for (int i = 0; i < n; ++i)
      if (shape_body[L * i + l] >= 0 && (lanes_run.first[l] < 0 || shape_body[L * i + l] < lanes_run.first[l]))
        lanes_run.first[l] = shape_body[L * i + l];
  }
  for (int i = 0; i < n; ++i) {
    if (shape_body[L * i] < 0) continue;  // (alike: no lane has a body for it)
    place[i] = shape_body[L * i] - lanes_run.first[0];
    for (int l = 1; l < L; ++l)
      if (shape_body[L * i + l] - lanes_run.first[l] != place[i]) return;
    lanes_run.length = std::max(lanes_run.length, place[i] + 1);
  }
  if (lanes_run.length == 0 || lanes_run.length > 2 * n) return;
  run[g] = lanes_run;
  run_place.resize(static_cast<size_t>(body_start[g] / L + n), -1);
  std::copy(place.begin(), place.end(), run_place.begin() + body_start[g] / L);
}

void WorldGroups::group_plane_reach(const Model& model, const ShapeFilter& filter, const WorldShapes& shapes, int g,
                                    std::vector<int>& read_planes) {
  constexpr int L = kLanes<Scalar>;
  constexpr std::size_t kReadPlanes = 8;  // (a model of many different planes reads its own beyond these)
  const int first_world = first[g], worlds = first[g + 1] - first_world;
  const std::vector<int>& first_shapes = shapes.world_others[first_world];
  const int n = static_cast<int>(first_shapes.size());
  const Scalar* transform = model.shape_transform.data();
  auto fixed_at = [&](int p, int q) {  // p on no body, where q is
    return model.shape_body[p] < 0 && std::equal(transform + 7 * p, transform + 7 * p + 7, transform + 7 * q);
  };
  for (const int code : shapes.plane_order(first_world)) {
    const int p0 = shapes.plane_of(first_world, code);
    std::uint64_t reach = 0;
    for (int i = 0; i < n; ++i)
      if (filter.may_collide(p0, first_shapes[i])) reach |= std::uint64_t{1} << i;
    bool alike_in_all = true, still = true;
    for (int l = 0; l < L; ++l) {
      const int p = shapes.plane_of(first_world + (l < worlds ? l : 0), code);
      plane_lanes.push_back(p);
      alike_in_all &= narrow_alike(model, p, p0);
      still &= fixed_at(p, p0);
    }
    int read = -1;
    if (alike_in_all) {
      const auto reads_as_p0 = [&](int q) { return narrow_alike(model, q, p0) && (!still || fixed_at(q, p0)); };
      const auto before = std::find_if(read_planes.begin(), read_planes.end(), reads_as_p0);
      read = before != read_planes.end() ? *before : p0;
      if (read == p0 && read_planes.size() < kReadPlanes) read_planes.push_back(p0);
    }
    plane_shapes.push_back(reach);
    plane_read.push_back(read);
    plane_still.push_back(alike_in_all && still);
  }
}

void WorldGroups::group_slots(const WorldShapes& shapes, int g) {
  constexpr int L = kLanes<Scalar>;
  const int first_world = first[g], start = static_cast<int>(slot_shapes.size());
  const int n = static_cast<int>(shapes.world_others[first_world].size());
  const int* shape_body = body.data() + body_start[g];
  std::vector<int> slot(n, -1);
  for (int i = 0; i < n; ++i) {
    for (int u = start; u < static_cast<int>(slot_shapes.size()) && slot[i] < 0 && shape_body[L * i] >= 0; ++u) {
      const int j = __builtin_ctzll(slot_shapes[u]);
      if (std::equal(shape_body + L * i, shape_body + L * (i + 1), shape_body + L * j)) slot[i] = u - start;
    }
    if (slot[i] < 0) {
      slot[i] = static_cast<int>(slot_shapes.size()) - start;
      slot_shapes.push_back(0);
    }
    slot_shapes[start + slot[i]] |= std::uint64_t{1} << i;
  }
  slot_pairs.resize(slot_shapes.size(), 0);
  const std::uint64_t* mask = shapes.world_pairs.data() + shapes.world_pair_start[first_world];
  for (int i = 0; i < n; ++i)
    for (std::uint64_t m = mask[i]; m != 0; m &= m - 1)
      slot_pairs[start + slot[i]] |= std::uint64_t{1} << slot[__builtin_ctzll(m)];
}

}  // namespace novaphy
