#include "engine/collision/shape_filter.h"

#include "engine/model/error.h"
#include "kernels/joint.h"

namespace novaphy {

ShapeFilter::ShapeFilter(const Model& model, bool self_collision) : model_(model), self_collision_(self_collision) {
  list_exclusions();
  link_bodies();
}

void ShapeFilter::list_exclusions() {
  // per shape, the shapes it is excluded with, ascending
  const Model& model = model_;
  exclude_start_.assign(model.shape_count + 1, 0);
  for (int e = 0; e < model.exclude_count; ++e)
    for (int k = 0; k < 2; ++k) {
      const int s = model.exclude_shape[2 * e + k];
      if (s < 0 || s >= model.shape_count)
        fail("exclude_shape[", e, "] names shape ", s, ", the model has ", model.shape_count);
      ++exclude_start_[s + 1];
    }
  for (int s = 0; s < model.shape_count; ++s) exclude_start_[s + 1] += exclude_start_[s];
  exclude_other_.resize(exclude_start_.back());
  std::vector<int> next(exclude_start_.begin(), exclude_start_.end() - 1);
  for (int e = 0; e < model.exclude_count; ++e) {
    const int a = model.exclude_shape[2 * e], b = model.exclude_shape[2 * e + 1];
    exclude_other_[next[a]++] = b;
    exclude_other_[next[b]++] = a;
  }
  for (int s = 0; s < model.shape_count; ++s)
    std::sort(exclude_other_.begin() + exclude_start_[s], exclude_other_.begin() + exclude_start_[s + 1]);
}

void ShapeFilter::link_bodies() {
  const Model& model = model_;
  std::vector<int> parent(model.body_count, -1), joint_of(model.body_count, -1);
  body_articulation_.assign(model.body_count, -1);
  for (int j = 0; j < model.joint_count; ++j) {
    const int child = model.joint_child[j];
    joint_of[child] = j;
    parent[child] = model.joint_parent[j];
    body_articulation_[child] = model.joint_articulation[j];
  }
  // a body's weld: its parent's where a Fixed joint holds it (the world's: -1), else itself; up the chain, memoised
  // (a body's parent may come after it in the model)
  constexpr int kUnknown = -2;
  body_weld_.assign(model.body_count, kUnknown);
  std::vector<int> path;
  for (int b = 0; b < model.body_count; ++b) {
    int at = b;
    while (at >= 0 && body_weld_[at] == kUnknown && joint_of[at] >= 0 &&
           static_cast<JointType>(model.joint_type[joint_of[at]]) == JointType::Fixed) {
      path.push_back(at);
      at = parent[at];
    }
    const int weld = at < 0 ? -1 : body_weld_[at] == kUnknown ? at : body_weld_[at];
    if (at >= 0) body_weld_[at] = weld;
    for (int p : path) body_weld_[p] = weld;
    path.clear();
  }
  // a weld's parent: the weld of the body above it, past massless links
  weld_parent_.assign(model.body_count, -1);
  for (int b = 0; b < model.body_count; ++b) {
    if (body_weld_[b] != b) continue;
    int above = parent[b];
    while (above >= 0 && model.body_mass[above] == 0) above = parent[above];
    weld_parent_[b] = above < 0 ? -1 : body_weld_[above];
  }
}

}  // namespace novaphy
