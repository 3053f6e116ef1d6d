#include "kernels/batch/topology.h"

#include <algorithm>

#include "kernels/batch/lane_math.h"

namespace novaphy {

using namespace lane_math;

namespace {

// link i's joint type, parent and starts, and its dofs' parents (last_dof: the deepest dof at or above
// each link, link i's set here)
template <typename T>
void link_tree(const ArticulationView& art, int i, BatchTopology<T>& topo, std::vector<int>& last_dof) {
  typename BatchTopology<T>::Link& L = topo.link[i];
  L.type = art.type(i);
  L.parent = art.parent(i);
  L.q_start = art.q_start(i);
  L.qd_start = art.qd_start(i);
  L.dof = art.dof(i);
  int up = L.parent < 0 ? -1 : last_dof[L.parent];
  for (int k = 0; k < L.dof; ++k) {
    topo.dof_parent[L.qd_start + k] = up;
    up = L.qd_start + k;
  }
  last_dof[i] = up;
  if (L.type == JointType::Revolute || L.type == JointType::Prismatic) topo.coord_of_dof[L.qd_start] = L.q_start;
}

// link i's joint frames, rotations and translations in precision T
template <typename T>
void link_frames(const ArticulationView& art, int i, typename BatchTopology<T>::Link& L) {
  const Transform Xp = art.X_p(i), Xc = art.X_c(i), Xci = Xc.inverse();
  const Vec3 a = art.axis(i);
  const Mat3 Rp = Xp.rotation();
  const Vec3 b = Xci.p;
  auto quat = [](const Quat& q, T* out) { out[0] = q.x(), out[1] = q.y(), out[2] = q.z(), out[3] = q.w(); };
  const Quat P0 = Xp.q * Xci.q;
  const Quat P1 = Xp.q * Quat(0, a.x(), a.y(), a.z()) * Xci.q;
  quat(P0, L.P0);
  quat(P1, L.P1);
  quat(Xp.q, L.Qp);
  quat(Xci.q, L.Qci);
  const Mat3 Rc = Xc.rotation();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) L.Rp[3 * r + c] = static_cast<T>(Rp(r, c)), L.Rc[3 * r + c] = static_cast<T>(Rc(r, c));
  const Vec3 T0 = Xp.p + Rp * b;
  Vec3 T1 = Vec3::Zero(), T2 = Vec3::Zero();
  if (L.type == JointType::Revolute) T1 = Rp * a.cross(b), T2 = Rp * a.cross(a.cross(b));
  if (L.type == JointType::Prismatic) T1 = Rp * a;
  const Vec3 ac = Rc * a;
  copy_n(Xp.p.data(), 3, L.tp);
  copy_n(T0.data(), 3, L.T0);
  copy_n(T1.data(), 3, L.T1);
  copy_n(T2.data(), 3, L.T2);
  copy_n(b.data(), 3, L.b);
  copy_n(Xc.p.data(), 3, L.tc);
  copy_n(ac.data(), 3, L.ac);
}

// each dof's ancestors ascending (ancestor_start, ancestors), where its row starts in the packed triangle, and
// each dof's descendants descending (descendant_start, descendants)
template <typename T>
void list_ancestors(BatchTopology<T>& topo) {
  topo.ancestor_start.assign(1, 0);
  topo.row_start.resize(topo.dof_count);
  for (int k = 0; k < topo.dof_count; ++k) {
    const size_t first = topo.ancestors.size();
    for (int j = topo.dof_parent[k]; j >= 0; j = topo.dof_parent[j]) topo.ancestors.push_back(j);
    std::reverse(topo.ancestors.begin() + first, topo.ancestors.end());
    topo.ancestor_start.push_back(static_cast<int>(topo.ancestors.size()));
    topo.row_start[k] = packed_index(k, 0);
  }
  std::vector<std::vector<int>> below(topo.dof_count);
  for (int k = topo.dof_count - 1; k >= 0; --k)
    for (int p = topo.ancestor_start[k]; p < topo.ancestor_start[k + 1]; ++p) below[topo.ancestors[p]].push_back(k);
  topo.descendant_start.assign(1, 0);
  for (const std::vector<int>& d : below) {
    topo.descendants.insert(topo.descendants.end(), d.begin(), d.end());
    topo.descendant_start.push_back(static_cast<int>(topo.descendants.size()));
  }
}

// each dof's ancestors as runs of consecutive dofs (run_start, ancestor_runs)
template <typename T>
void list_ancestor_runs(BatchTopology<T>& topo) {
  auto& runs = topo.ancestor_runs;
  topo.run_start.assign(1, 0);
  for (int k = 0; k < topo.dof_count; ++k) {
    for (int p = topo.ancestor_start[k]; p < topo.ancestor_start[k + 1]; ++p) {
      const bool extends =
          static_cast<int>(runs.size()) > topo.run_start[k] && runs.back().dof + runs.back().count == topo.ancestors[p];
      if (extends)
        ++runs.back().count;
      else
        runs.push_back({topo.ancestors[p], 1});
    }
    topo.run_start.push_back(static_cast<int>(runs.size()));
  }
}

// each link's dofs, its ancestors' and its own ascending (link_dof_start, link_dofs)
template <typename T>
void list_link_dofs(BatchTopology<T>& topo, const std::vector<int>& last_dof) {
  topo.link_dof_start.assign(1, 0);
  const int n = static_cast<int>(topo.link.size());
  for (int i = 0; i < n; ++i) {
    const int d = last_dof[i];
    if (d >= 0) {
      topo.link_dofs.insert(topo.link_dofs.end(), topo.ancestors.begin() + topo.ancestor_start[d],
                            topo.ancestors.begin() + topo.ancestor_start[d + 1]);
      topo.link_dofs.push_back(d);
    }
    topo.link_dof_start.push_back(static_cast<int>(topo.link_dofs.size()));
  }
}

}  // namespace

template <typename T>
BatchTopology<T>::BatchTopology(const ArticulationView& art) {
  const int n = art.link_count();
  link.resize(n);
  coord_count = art.coord_count();
  dof_count = art.dof_count();
  dof_parent.assign(dof_count, -1);
  coord_of_dof.assign(dof_count, -1);
  std::vector<int> last_dof(n, -1);  // deepest dof at or above each link
  for (int i = 0; i < n; ++i) {
    link_tree(art, i, *this, last_dof);
    link_frames<T>(art, i, link[i]);
  }
  list_ancestors(*this);
  list_ancestor_runs(*this);
  list_link_dofs(*this, last_dof);
}

template <typename T>
void batch_set_params(const BatchTopology<T>& topo, const ArticulationView& art, int lane, V<T>* data) {
  const int n = static_cast<int>(topo.link.size()), nv = topo.dof_count;
  const BatchParamOffsets at = batch_param_offsets(topo);
  V<T>* x = data;
  for (int i = 0; i < n; ++i) {
    const int b = art.body(i);
    x[at.mass + i][lane] = static_cast<T>(art.body_mass[b]);
    for (int m = 0; m < 3; ++m) x[at.com + 3 * i + m][lane] = static_cast<T>(art.body_com[3 * b + m]);
    const int order[6] = {0, 4, 8, 1, 2, 5};  // xx yy zz xy xz yz of the row-major 3x3
    for (int m = 0; m < 6; ++m) x[at.inertia + 6 * i + m][lane] = static_cast<T>(art.body_inertia[9 * b + order[m]]);
  }
  for (int k = 0; k < nv; ++k) {
    const int g = art.qd_begin() + k;
    x[at.armature + k][lane] = static_cast<T>(art.joint_armature[g]);
    x[at.damping + k][lane] = static_cast<T>(art.joint_damping[g]);
    x[at.stiffness + k][lane] = static_cast<T>(art.joint_stiffness[g]);
    const int c = topo.coord_of_dof[k];  // spring rest positions of the one-coordinate joints
    x[at.q_ref + k][lane] = static_cast<T>(c < 0 ? 0 : art.joint_q_ref[art.q_begin() + c]);
  }
  for (int m = 0; m < 3; ++m) x[at.gravity + m][lane] = static_cast<T>(art.world_gravity[m]);
}

template <typename T>
void BatchWork<T>::resize(const BatchTopology<T>& topo) {
  const size_t n = topo.link.size(), nc = topo.coord_count, nv = topo.dof_count;
#define NOVAPHY_RESIZE_WORK(name, count, doc) name.resize(count);
  NOVAPHY_BATCH_WORK(NOVAPHY_RESIZE_WORK)
#undef NOVAPHY_RESIZE_WORK
}

template <typename T>
std::size_t BatchWork<T>::bytes() const {
  std::size_t count = bodies.size();
#define NOVAPHY_COUNT_WORK(name, count_, doc) count += name.size();
  NOVAPHY_BATCH_WORK(NOVAPHY_COUNT_WORK)
#undef NOVAPHY_COUNT_WORK
  return count * sizeof(Lanes<T>);
}

#define NOVAPHY_INSTANTIATE(T)      \
  template struct BatchTopology<T>; \
  template struct BatchWork<T>;     \
  template void batch_set_params(const BatchTopology<T>&, const ArticulationView&, int, Lanes<T>*);
NOVAPHY_INSTANTIATE(float)
NOVAPHY_INSTANTIATE(double)
#undef NOVAPHY_INSTANTIATE

}  // namespace novaphy
