// ShapeFilter: which pairs of shapes may ever collide, by the model alone (bodies, worlds, collision groups and
// masks, excluded pairs, joints) and the self_collision option; built once for a model, read by every collide.
#pragma once

#include <algorithm>
#include <vector>

#include "engine/model/model.h"

namespace novaphy {

// shape s collides with no shape by the model's filter (its group or mask empty, both under Mujoco's rule)
inline bool shape_visual_only(const Model& model, int s) {
  const int group = model.shape_collision_group[s], mask = model.shape_collision_mask[s];
  return model.collision_filter == CollisionFilter::Mujoco ? group == 0 && mask == 0 : group == 0 || mask == 0;
}

// keeps a reference to the model, which must outlive it
class ShapeFilter {
 public:
  // self_collision: links of one articulation collide (never a parent with its child; CollisionOptions)
  ShapeFilter(const Model& model, bool self_collision);

  // shapes a and b may collide: on different bodies, in one world (or either in none), each in a group the other's
  // mask takes (both under MuJoCo's rule: either), not an excluded pair, not on bodies welded together, not a body
  // and its parent, and not of one articulation where self_collision is off. Welded, as MuJoCo's filter: a body held
  // to its parent by a Fixed joint counts as that parent (to the world: as the world, so it meets only moving
  // bodies), and the parent rule applies to those it counts as (inline: the broad phase's test of every pair it lets
  // through)
  bool may_collide(int a, int b) const {
    const int ba = model_.shape_body[a], bb = model_.shape_body[b];
    if (ba == bb) return false;
    const int wa = model_.shape_world[a], wb = model_.shape_world[b];
    if (wa >= 0 && wb >= 0 && wa != wb) return false;
    const bool ab = (model_.shape_collision_group[a] & model_.shape_collision_mask[b]) != 0;
    const bool ba_ = (model_.shape_collision_group[b] & model_.shape_collision_mask[a]) != 0;
    if (model_.collision_filter == CollisionFilter::Mujoco ? !(ab || ba_) : !(ab && ba_)) return false;
    if (excluded(a, b)) return false;
    const int weld_a = ba < 0 ? -1 : body_weld_[ba], weld_b = bb < 0 ? -1 : body_weld_[bb];
    if (weld_a == weld_b) return false;
    if (weld_a < 0 || weld_b < 0) return true;
    if (weld_parent_[weld_a] == weld_b || weld_parent_[weld_b] == weld_a) return false;
    return self_collision_ || body_articulation_[ba] != body_articulation_[bb];
  }
  // shape s collides with no shape (shape_visual_only)
  bool visual_only(int s) const { return shape_visual_only(model_, s); }
  // shapes a and b are an excluded pair (the model's exclude_shape)
  bool excluded(int a, int b) const {
    const auto begin = exclude_other_.begin() + exclude_start_[a], end = exclude_other_.begin() + exclude_start_[a + 1];
    return begin != end && std::binary_search(begin, end, b);
  }

 private:
  // the constructor's stages, in this order:
  // exclude_start_ and exclude_other_ from the model's excluded shape pairs
  void list_exclusions();
  // each body's weld (the body it counts as), its weld's parent's weld, and its articulation
  void link_bodies();

  const Model& model_;
  bool self_collision_;
  // per shape s, the shapes it never collides with, ascending: exclude_other_[exclude_start_[s] .. exclude_start_[s +
  // 1])
  std::vector<int> exclude_start_, exclude_other_;
  // per body: the body it counts as, up its Fixed joints (-1: the world); per such body, what its parent (through
  // its joint, skipping massless links: a MuJoCo body of several joints is a chain of them) counts as
  std::vector<int> body_weld_, weld_parent_;
  std::vector<int> body_articulation_;
};

}  // namespace novaphy
