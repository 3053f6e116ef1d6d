#include "engine/articulation_batches.h"

#include <omp.h>

#include <algorithm>
#include <map>

#include "kernels/batch.h"

namespace novaphy {

namespace {

// what articulations must share to be batched: joint types, tree, frames and axes
std::vector<double> topology_key(const ArticulationView& art) {
  std::vector<double> key;
  for (int i = 0; i < art.link_count(); ++i) {
    key.push_back(static_cast<double>(art.type(i)));
    key.push_back(art.parent(i));
    const int j = art.joint_begin + i;
    key.insert(key.end(), art.joint_X_p + 7 * j, art.joint_X_p + 7 * j + 7);
    key.insert(key.end(), art.joint_X_c + 7 * j, art.joint_X_c + 7 * j + 7);
    key.insert(key.end(), art.joint_axis + 3 * j, art.joint_axis + 3 * j + 3);
  }
  return key;
}

template <typename T>
class Batches final : public ArticulationBatches {
  using V = Lanes<T>;
  static constexpr int W = kLanes<T>;

  // per block: the parameters (BatchParams' arrays, in this order), H / its factor, S, o
  struct Group {
    BatchTopology<T> topo;
    std::vector<int> arts;  // lane slots, block after block; a partial last block repeats its first world
    int world_count = 0;
    int blocks = 0;
    int param_size = 0;
    std::vector<V> params, H, S, origin;
    std::vector<int> coord_of_dof;  // Revolute / Prismatic dofs: their coordinate, else -1
    bool enabled = true;
    bool factored = false;  // H of every block factored by an earlier step
    bool refactor = true;   // this step computes and factors H

    explicit Group(const ArticulationView& art) : topo(art) {}
    BatchParams<T> block_params(int b) const {
      const int n = static_cast<int>(topo.link.size()), nv = topo.dof_count;
      const V* x = params.data() + static_cast<size_t>(b) * param_size;
      return {x, x + n, x + 4 * n, x + 10 * n, x + 10 * n + nv, x + 10 * n + 2 * nv, x + 10 * n + 3 * nv};
    }
    V* block_H(int b) { return H.data() + static_cast<size_t>(b) * topo.packed_size(); }
    const V* block_H(int b) const { return H.data() + static_cast<size_t>(b) * topo.packed_size(); }
    V* block_S(int b) { return S.data() + static_cast<size_t>(b) * 6 * topo.dof_count; }
    const V* block_S(int b) const { return S.data() + static_cast<size_t>(b) * 6 * topo.dof_count; }
  };

  struct Slot {
    int group = -1, block = 0, lane = 0;
  };

 public:
  Batches(const Model& model, const std::vector<ArticulationView>& art, const std::vector<std::uint8_t>& batched)
      : art_(art), gravity_(model.gravity), slot_(art.size()) {
    std::map<std::vector<double>, int> index;
    for (size_t a = 0; a < art.size(); ++a) {
      if (!batched[a]) continue;
      const auto [it, added] = index.try_emplace(topology_key(art[a]), static_cast<int>(groups_.size()));
      if (added) groups_.emplace_back(art[a]);
      groups_[it->second].arts.push_back(static_cast<int>(a));
    }
    for (int g = 0; g < static_cast<int>(groups_.size()); ++g) {
      Group& G = groups_[g];
      G.world_count = static_cast<int>(G.arts.size());
      G.blocks = (G.world_count + W - 1) / W;
      for (int k = 0; k < G.world_count; ++k) slot_[G.arts[k]] = {g, k / W, k % W};
      G.arts.resize(static_cast<size_t>(G.blocks) * W, -1);
      for (int b = 0; b < G.blocks; ++b)
        for (int l = 0; l < W; ++l)
          if (G.arts[b * W + l] < 0) G.arts[b * W + l] = G.arts[b * W];
      const int n = static_cast<int>(G.topo.link.size()), nv = G.topo.dof_count;
      G.param_size = 10 * n + 4 * nv;
      G.params.resize(static_cast<size_t>(G.blocks) * G.param_size);
      G.H.resize(static_cast<size_t>(G.blocks) * G.topo.packed_size());
      G.S.resize(static_cast<size_t>(G.blocks) * 6 * nv);
      G.origin.resize(static_cast<size_t>(G.blocks) * 3);
      G.coord_of_dof.assign(nv, -1);
      for (const auto& L : G.topo.link)
        if (L.type == JointType::Revolute || L.type == JointType::Prismatic) G.coord_of_dof[L.qd_start] = L.q_start;
      for (int b = 0; b < G.blocks; ++b) gather_params(G, b);
      for (int b = 0; b < G.blocks; ++b) blocks_.push_back({g, b});
    }
    work_.resize(std::max(1, omp_get_max_threads()));
    for (auto& per_thread : work_) {
      per_thread.resize(groups_.size());
      for (size_t g = 0; g < groups_.size(); ++g) per_thread[g].resize(groups_[g].topo);
    }
  }

  void enable(int max_dofs) override {
    for (Group& G : groups_) {
      const bool on = G.topo.dof_count < max_dofs;
      if (!on) G.factored = false;
      G.enabled = on;
    }
  }

  bool active(int a) const override { return slot_[a].group >= 0 && groups_[slot_[a].group].enabled; }

  void dynamics(const State& in, const Control& control, const Scalar* tau, Scalar dt_, bool refactor, bool fuse,
                Scalar* qd_out, int* factor_failure, int threads) override {
    for (Group& G : groups_) G.refactor = refactor || !G.factored;
    for_each_block(threads, [&](Group& G, int b, BatchWork<T>& w) {
      const T dt = static_cast<T>(dt_);
      const BatchTopology<T>& topo = G.topo;
      const int nv = topo.dof_count;
      const int* arts = &G.arts[b * W];
      gather(arts, in.joint_q.data(), art_q_begin(), topo.coord_count, w.q.data());
      gather(arts, in.joint_qd.data(), art_qd_begin(), nv, w.qd.data());
      V* o = &G.origin[3 * b];
      V* S = G.block_S(b);
      const BatchParams<T> P = G.block_params(b);
      batch_kinematics(topo, w.q.data(), w, o);
      batch_subspace(topo, w, o, S);
      batch_velocity(topo, S, w.qd.data(), w);
      batch_link_inertia(topo, P, o, w);
      const V* f_ext = gather_wrenches(G, arts, in.body_f.data(), o, w) ? w.f_ext.data() : nullptr;
      V g[3];
      for (int k = 0; k < 3; ++k) g[k] = V{} + static_cast<T>(gravity_[k]);
      batch_bias(topo, S, g, f_ext, w, w.tau.data());

      // x = tau - bias - damping qd + kd (v_t - qd) - K_s (q_end - q_ref) + ke (q_t - q_end), q_end = q + dt qd
      V* x = w.x.data();
      gather(arts, tau, art_qd_begin(), nv, x);
      for (int k = 0; k < nv; ++k) x[k] -= w.tau[k];
      add_implicit_terms(G, arts, control, P, dt, w);

      V* H = G.block_H(b);
      IntLanes<T> bad = IntLanes<T>{} - 1;
      if (G.refactor) {
        batch_mass_matrix(topo, P, S, w, H);
        for (int k = 0; k < nv; ++k) H[packed_index(k, k)] += w.diag[k];
        bad = batch_factor(topo, H, fuse ? x : nullptr);
        if (fuse)
          batch_solve_lower(topo, H, x);
        else
          batch_solve(topo, H, x);
      } else {
        batch_solve(topo, H, x);
      }
      for (int l = 0; l < W && b * W + l < G.world_count; ++l) {
        const int a = arts[l];
        if (bad[l] >= 0) factor_failure[a] = art_[a].qd_begin() + static_cast<int>(bad[l]);
        Scalar* out = qd_out + art_[a].qd_begin();
        for (int k = 0; k < nv; ++k) out[k] = static_cast<T>(w.qd[k][l] + dt * x[k][l]);
      }
    });
    for (Group& G : groups_)
      if (G.enabled) G.factored = true;
  }

  void integrate(const State& in, const Scalar* qd, Scalar dt, Scalar* q_out, int threads) override {
    for_each_block(threads, [&](Group& G, int b, BatchWork<T>& w) {
      const int* arts = &G.arts[b * W];
      gather(arts, in.joint_q.data(), art_q_begin(), G.topo.coord_count, w.q.data());
      gather(arts, qd, art_qd_begin(), G.topo.dof_count, w.qd.data());
      batch_integrate(G.topo, w.q.data(), w.qd.data(), static_cast<T>(dt), w.q_next.data());
      scatter(G, b, w.q_next.data(), art_q_begin(), G.topo.coord_count, q_out);
    });
  }

  void store_bodies(State& out, int threads) override {
    for_each_block(threads, [&](Group& G, int b, BatchWork<T>& w) {
      const BatchTopology<T>& topo = G.topo;
      const int* arts = &G.arts[b * W];
      gather(arts, out.joint_q.data(), art_q_begin(), topo.coord_count, w.q.data());
      gather(arts, out.joint_qd.data(), art_qd_begin(), topo.dof_count, w.qd.data());
      V* o = &G.origin[3 * b];
      V* S = G.block_S(b);
      batch_kinematics(topo, w.q.data(), w, o);
      batch_subspace(topo, w, o, S);
      batch_velocity(topo, S, w.qd.data(), w);
      const BatchParams<T> P = G.block_params(b);
      for (size_t i = 0; i < topo.link.size(); ++i) {
        const V* R = &w.R[9 * i];
        const V* v = &w.v[6 * i];
        const V* com = P.com + 3 * i;
        V c[3], v_com[3];  // centre of mass relative to o, its velocity
        for (int m = 0; m < 3; ++m)
          c[m] = R[3 * m] * com[0] + R[3 * m + 1] * com[1] + R[3 * m + 2] * com[2] + w.p[3 * i + m] - o[m];
        v_com[0] = v[3] + v[1] * c[2] - v[2] * c[1];
        v_com[1] = v[4] + v[2] * c[0] - v[0] * c[2];
        v_com[2] = v[5] + v[0] * c[1] - v[1] * c[0];
        for (int l = 0; l < W && b * W + l < G.world_count; ++l) {
          const int body = art_[arts[l]].body(static_cast<int>(i));
          Scalar* X = out.body_q.data() + 7 * body;
          for (int m = 0; m < 3; ++m) X[m] = w.p[3 * i + m][l];
          for (int m = 0; m < 4; ++m) X[3 + m] = w.Q[4 * i + m][l];
          Scalar* qd = out.body_qd.data() + 6 * body;
          for (int m = 0; m < 3; ++m) qd[m] = v_com[m][l], qd[3 + m] = v[m][l];
        }
      }
    });
  }

  void solve_mass(int a, Scalar* x) const override {
    const Slot& s = slot_[a];
    const Group& G = groups_[s.group];
    batch_solve_lane(G.topo, G.block_H(s.block), s.lane, x);
  }

  void point_jacobian(int a, int link, const Vec3& p, const Vec3& d, Scalar sign, Scalar* J) const override {
    const Slot& s = slot_[a];
    const Group& G = groups_[s.group];
    const V* S = G.block_S(s.block);
    const V* o = &G.origin[3 * s.block];
    const Vec3 r = p - Vec3(o[0][s.lane], o[1][s.lane], o[2][s.lane]);
    const Vec3 rxd = r.cross(d);
    const auto& topo = G.topo;
    for (int i = link; i >= 0; i = topo.link[i].parent)
      for (int k = topo.link[i].qd_start; k < topo.link[i].qd_start + topo.link[i].dof; ++k) {
        const V* s6 = S + 6 * k;
        const Scalar ang = rxd.x() * s6[0][s.lane] + rxd.y() * s6[1][s.lane] + rxd.z() * s6[2][s.lane];
        const Scalar lin = d.x() * s6[3][s.lane] + d.y() * s6[4][s.lane] + d.z() * s6[5][s.lane];
        J[k] += sign * (lin + ang);
      }
  }

  int group_count() const override { return static_cast<int>(groups_.size()); }
  int block_count() const override { return static_cast<int>(blocks_.size()); }
  int lanes() const override { return W; }
  std::size_t bytes() const override {
    std::size_t n = 0;
    for (const Group& G : groups_)
      n += (G.params.size() + G.H.size() + G.S.size() + G.origin.size()) * sizeof(V) + G.arts.size() * sizeof(int);
    for (const auto& per_thread : work_)
      for (const BatchWork<T>& w : per_thread)
        for (const auto* v : {&w.Q, &w.p, &w.R, &w.v, &w.a, &w.f, &w.I, &w.vrel, &w.q, &w.qd, &w.x, &w.tau, &w.diag,
                              &w.f_ext, &w.q_next})
          n += v->size() * sizeof(V);
    return n;
  }

 private:
  // per-articulation starts, for gather and scatter
  struct Begin {
    const std::vector<ArticulationView>* art;
    bool coords;
    int operator()(int a) const { return coords ? (*art)[a].q_begin() : (*art)[a].qd_begin(); }
  };
  Begin art_q_begin() const { return {&art_, true}; }
  Begin art_qd_begin() const { return {&art_, false}; }

  // out[k][l] = field[begin(arts[l]) + k]
  template <typename B>
  static void gather(const int* arts, const Scalar* field, B begin, int count, V* out) {
    for (int l = 0; l < W; ++l) {
      const Scalar* x = field + begin(arts[l]);
      for (int k = 0; k < count; ++k) out[k][l] = static_cast<T>(x[k]);
    }
  }
  template <typename B>
  void scatter(const Group& G, int b, const V* in, B begin, int count, Scalar* field) const {
    for (int l = 0; l < W && b * W + l < G.world_count; ++l) {
      Scalar* x = field + begin(G.arts[b * W + l]);
      for (int k = 0; k < count; ++k) x[k] = in[k][l];
    }
  }

  void gather_params(Group& G, int b) {
    const BatchParams<T> P = G.block_params(b);
    auto put = [](const V* at, int k, int l, Scalar value) { const_cast<V*>(at)[k][l] = static_cast<T>(value); };
    for (int l = 0; l < W; ++l) {
      const ArticulationView& art = art_[G.arts[b * W + l]];
      for (int i = 0; i < art.link_count(); ++i) {
        const int body = art.body(i);
        put(P.mass, i, l, art.body_mass[body]);
        for (int m = 0; m < 3; ++m) put(P.com, 3 * i + m, l, art.body_com[3 * body + m]);
        const Scalar* I = art.body_inertia + 9 * body;
        const int order[6] = {0, 4, 8, 1, 2, 5};
        for (int m = 0; m < 6; ++m) put(P.inertia, 6 * i + m, l, I[order[m]]);
      }
      for (int k = 0; k < art.dof_count(); ++k) {
        const int g = art.qd_begin() + k;
        put(P.armature, k, l, art.joint_armature[g]);
        put(P.damping, k, l, art.joint_damping[g]);
        put(P.stiffness, k, l, art.joint_stiffness[g]);
        const int c = G.coord_of_dof[k];
        put(P.q_ref, k, l, c < 0 ? 0 : art.joint_q_ref[art.q_begin() + c]);
      }
    }
  }

  // applied wrenches [f at the centre of mass; torque], world, as spatial forces about o; false if none
  bool gather_wrenches(const Group& G, const int* arts, const Scalar* body_f, const V* o, BatchWork<T>& w) const {
    const int n = static_cast<int>(G.topo.link.size());
    bool any = false;
    for (int l = 0; l < W && !any; ++l)
      for (int i = 0; i < n && !any; ++i) {
        const Scalar* f = body_f + 6 * art_[arts[l]].body(i);
        for (int m = 0; m < 6; ++m) any |= f[m] != 0;
      }
    if (!any) return false;
    for (int i = 0; i < n; ++i) {
      V* F = &w.f_ext[6 * i];
      for (int l = 0; l < W; ++l) {
        const Scalar* f = body_f + 6 * art_[arts[l]].body(i);
        for (int m = 0; m < 3; ++m) F[3 + m][l] = static_cast<T>(f[m]), F[m][l] = static_cast<T>(f[3 + m]);
      }
      // torque about o: t + (c - o) x f, c the centre of mass
      const V* R = &w.R[9 * i];
      const BatchParams<T> P = G.block_params(static_cast<int>((arts - G.arts.data()) / W));
      const V* com = P.com + 3 * i;
      V c[3];
      for (int m = 0; m < 3; ++m)
        c[m] = R[3 * m] * com[0] + R[3 * m + 1] * com[1] + R[3 * m + 2] * com[2] + w.p[3 * i + m] - o[m];
      F[0] += c[1] * F[5] - c[2] * F[4];
      F[1] += c[2] * F[3] - c[0] * F[5];
      F[2] += c[0] * F[4] - c[1] * F[3];
    }
    return true;
  }

  // springs, dampers and PD drives at the end of the step into w.x, their diagonal into w.diag
  void add_implicit_terms(const Group& G, const int* arts, const Control& control, const BatchParams<T>& P, T dt,
                          BatchWork<T>& w) const {
    const int nv = G.topo.dof_count;
    for (int k = 0; k < nv; ++k) {
      V kd, vt, ke, qt;
      for (int l = 0; l < W; ++l) {
        const int g = art_[arts[l]].qd_begin() + k;
        kd[l] = static_cast<T>(control.joint_target_kd[g]);
        vt[l] = static_cast<T>(control.joint_target_vel[g]);
        ke[l] = static_cast<T>(control.joint_target_ke[g]);
        qt[l] = static_cast<T>(control.joint_target_pos[g]);
      }
      const V qd = w.qd[k];
      w.x[k] += -P.damping[k] * qd + kd * (vt - qd);
      w.diag[k] = dt * (P.damping[k] + kd);
      const int c = G.coord_of_dof[k];
      if (c < 0) continue;
      const V q_end = w.q[c] + dt * qd;
      w.x[k] += -P.stiffness[k] * (q_end - P.q_ref[k]) + ke * (qt - q_end);
      w.diag[k] += dt * dt * (P.stiffness[k] + ke);
    }
  }

  template <typename F>
  void for_each_block(int threads, F&& f) {
    const int count = static_cast<int>(blocks_.size());
    const int n = std::min<int>(threads > 0 ? threads : static_cast<int>(work_.size()), static_cast<int>(work_.size()));
#pragma omp parallel for schedule(static) num_threads(n)
    for (int k = 0; k < count; ++k) {
      Group& G = groups_[blocks_[k].first];
      if (!G.enabled) continue;
      f(G, blocks_[k].second, work_[omp_get_thread_num()][blocks_[k].first]);
    }
  }

  const std::vector<ArticulationView>& art_;
  Vec3 gravity_;
  std::vector<Group> groups_;
  std::vector<std::pair<int, int>> blocks_;      // (group, block) in order
  std::vector<Slot> slot_;                       // per articulation
  std::vector<std::vector<BatchWork<T>>> work_;  // per thread, per group
};

}  // namespace

std::unique_ptr<ArticulationBatches> ArticulationBatches::make(const Model& model,
                                                               const std::vector<ArticulationView>& art,
                                                               const std::vector<std::uint8_t>& batched,
                                                               Precision precision) {
  if (precision == Precision::Float32) return std::make_unique<Batches<float>>(model, art, batched);
  return std::make_unique<Batches<double>>(model, art, batched);
}

}  // namespace novaphy
