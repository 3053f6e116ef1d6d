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
  // mask takes (both under MuJoCo's rule: either), not an excluded pair, not a parent body and its child, and not of
  // one articulation where self_collision is off (inline: the broad phase's test of every pair it lets through)
  bool may_collide(int a, int b) const {
    const int ba = model_.shape_body[a], bb = model_.shape_body[b];
    if (ba == bb) return false;
    const int wa = model_.shape_world[a], wb = model_.shape_world[b];
    if (wa >= 0 && wb >= 0 && wa != wb) return false;
    const bool ab = (model_.shape_collision_group[a] & model_.shape_collision_mask[b]) != 0;
    const bool ba_ = (model_.shape_collision_group[b] & model_.shape_collision_mask[a]) != 0;
    if (model_.collision_filter == CollisionFilter::Mujoco ? !(ab || ba_) : !(ab && ba_)) return false;
    if (excluded(a, b)) return false;
    if (ba < 0 || bb < 0) return true;
    if (body_parent_[ba] == bb || body_parent_[bb] == ba) return false;
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
  // each body's parent (skipping massless links) and articulation
  void link_bodies();

  const Model& model_;
  bool self_collision_;
  // per shape s, the shapes it never collides with, ascending: exclude_other_[exclude_start_[s] .. exclude_start_[s +
  // 1])
  std::vector<int> exclude_start_, exclude_other_;
  std::vector<int> body_parent_;  // parent body of each body through its joint (skipping massless links), -1
  std::vector<int> body_articulation_;
};

}  // namespace novaphy
