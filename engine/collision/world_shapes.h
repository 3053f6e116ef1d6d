// WorldShapes: the shapes that collide, sorted per world (planes apart from the others, those of no world apart),
// and each world's pairs the filter allows: as a bit mask per shape where the world has few shapes, else by sweep
// and prune at each collide. Built once for a model on its ShapeFilter; read-only after.
#pragma once

#include <cstdint>
#include <vector>

#include "engine/collision/shape_filter.h"
#include "engine/model/model.h"

namespace novaphy {

class WorldShapes {
 public:
  // a world of at most this many shapes tests the pairs may_collide allows, from a bit mask per shape worked out
  // once; a larger one sweeps and prunes
  static constexpr int kMaskedWorldShapes = 64;

  // the shapes of `model` that are not visual_only by `filter`
  WorldShapes(const Model& model, const ShapeFilter& filter);

  // world w's planes, its own and those of no world, in index order (the order it meets them): k >= 0
  // its k-th own plane, -1 - j the j-th of no world
  std::vector<int> plane_order(int w) const;
  // the plane of world w that plane_order names by `code`
  int plane_of(int w, int code) const { return code >= 0 ? world_planes[w][code] : shared_planes[-1 - code]; }

  std::vector<int> planes;                        // shape indices of the planes, ascending
  std::vector<int> moving_planes;                 // those on a body
  std::vector<std::vector<int>> world_others;     // non-plane shapes of each world, in index order
  std::vector<std::vector<int>> world_planes;     // planes of each world, in index order
  std::vector<int> shared_others, shared_planes;  // shapes of no world: every world meets them
  // per world of few shapes, where its masks start in world_pairs (-1: it sweeps); per shape of it, bit j set
  // where it may collide with the world's shape j after it
  std::vector<int> world_pair_start;
  std::vector<std::uint64_t> world_pairs;
  std::vector<int> shape_part;  // [shape] its world where it is not a plane and has one, else -1

 private:
  // the constructor's stages, in this order:
  // the colliding shapes into planes and others, per world or of no world
  void sort_shapes(const Model& model, const ShapeFilter& filter);
  // per world of few shapes its pairs' masks
  void mask_pairs(const ShapeFilter& filter);
};

}  // namespace novaphy
