#include "engine/collision/world_shapes.h"

namespace novaphy {

WorldShapes::WorldShapes(const Model& model, const ShapeFilter& filter) {
  sort_shapes(model, filter);
  mask_pairs(filter);
}

void WorldShapes::sort_shapes(const Model& model, const ShapeFilter& filter) {
  world_others.resize(model.world_count);
  world_planes.resize(model.world_count);
  shape_part.assign(model.shape_count, -1);
  for (int s = 0; s < model.shape_count; ++s) {
    if (filter.visual_only(s)) continue;  // the broad phase never sees it
    const int w = model.shape_world[s];
    if (model.shape_type[s] == static_cast<int>(ShapeType::Plane)) {
      planes.push_back(s);
      if (model.shape_body[s] >= 0) moving_planes.push_back(s);
      (w < 0 ? shared_planes : world_planes[w]).push_back(s);
      continue;
    }
    (w < 0 ? shared_others : world_others[w]).push_back(s);
    shape_part[s] = w;
  }
}

void WorldShapes::mask_pairs(const ShapeFilter& filter) {
  const int world_count = static_cast<int>(world_others.size());
  world_pair_start.assign(world_count, -1);
  for (int w = 0; w < world_count; ++w) {
    const std::vector<int>& shapes = world_others[w];
    if (shapes.size() > kMaskedWorldShapes) continue;
    world_pair_start[w] = static_cast<int>(world_pairs.size());
    for (size_t i = 0; i < shapes.size(); ++i) {
      std::uint64_t mask = 0;
      for (size_t j = i + 1; j < shapes.size(); ++j)
        if (filter.may_collide(shapes[i], shapes[j])) mask |= std::uint64_t{1} << j;
      world_pairs.push_back(mask);
    }
  }
}

std::vector<int> WorldShapes::plane_order(int w) const {
  const std::vector<int>& own = world_planes[w];
  std::vector<int> order;
  for (size_t i = 0, j = 0; i < own.size() || j < shared_planes.size();) {
    const bool take_own = j == shared_planes.size() || (i < own.size() && own[i] < shared_planes[j]);
    order.push_back(take_own ? static_cast<int>(i++) : -1 - static_cast<int>(j++));
  }
  return order;
}

}  // namespace novaphy
