#include "engine/collision/shape_filter.h"

#include "engine/model/error.h"

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
  body_parent_.assign(model.body_count, -1);
  body_articulation_.assign(model.body_count, -1);
  for (int j = 0; j < model.joint_count; ++j) {
    // the parent through massless links (a MuJoCo body with several joints is a chain of them)
    int parent = model.joint_parent[j];
    while (parent >= 0 && model.body_mass[parent] == 0) parent = body_parent_[parent];
    body_parent_[model.joint_child[j]] = parent;
    body_articulation_[model.joint_child[j]] = model.joint_articulation[j];
  }
}

}  // namespace novaphy
