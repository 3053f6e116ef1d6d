#include "engine/articulation_batches.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <numeric>
#include <type_traits>

#include "engine/parallel.h"
#include "kernels/batch.h"
#include "kernels/batch_pgs.h"
#include "kernels/lane_transpose.h"
#include "kernels/stream.h"

namespace novaphy {

namespace {

// what articulations must share to be batched: joint types, tree, frames, axes and welded bodies
std::vector<double> topology_key(const ArticulationView& art, const std::vector<WeldedBody>& welded) {
  std::vector<double> key;
  for (int i = 0; i < art.link_count(); ++i) {
    key.push_back(static_cast<double>(art.type(i)));
    key.push_back(art.parent(i));
    const int j = art.joint_begin + i;
    key.insert(key.end(), art.joint_X_p + 7 * j, art.joint_X_p + 7 * j + 7);
    key.insert(key.end(), art.joint_X_c + 7 * j, art.joint_X_c + 7 * j + 7);
    key.insert(key.end(), art.joint_axis + 3 * j, art.joint_axis + 3 * j + 3);
  }
  for (const WeldedBody& b : welded) {
    key.push_back(b.link);
    double x[7];
    b.offset.to_array(x);
    key.insert(key.end(), x, x + 7);
  }
  return key;
}

template <typename T>
class Batches final : public ArticulationBatches {
  using V = Lanes<T>;
  static constexpr int W = kLanes<T>;

  struct Weld {  // a welded body every world of the group has
    int link;
    T q[4], p[3];  // its pose in the link frame
  };

  // lane slots run block after block; a partial last block repeats its first world in the others
  struct Group {
    BatchTopology<T> topo;
    std::vector<Weld> welds;
    std::vector<int> arts;           // per slot
    std::vector<int> q_off, qd_off;  // per slot: the articulation's first coordinate and dof
    std::vector<int> body;           // per slot: its link bodies, then its welded bodies
    // per body of a world (links, then welds): its place among the world's bodies as the model numbers
    // them (a welded body's number falls between its links'), where its rows are written
    std::vector<int> body_place;
    std::vector<std::uint8_t> contiguous;  // per block: its worlds' bodies, each world's in one run, one after another
    int world_count = 0;
    int blocks = 0;
    int param_size = 0;
    bool shared_params = false;  // every world's parameters the same: one block's worth kept, read by all
    // per block: the parameters (BatchParams' arrays in order, then, with welded bodies, every
    // body's own centre of mass), H and its factor, the motion subspace and o of the last kinematics
    std::vector<V> params, H, S, origin;
    std::vector<int> rotational;  // dofs angular damping scales: Revolute ones and Ball's and Free's angular ones
    std::vector<int> limited;     // Revolute / Prismatic dofs with a finite limit in some world
    std::vector<V> limits;        // per block: [limited][2] lower and upper limit
    // where its blocks' kept limit impulses start in the solver's array (limit_cells): per block
    // [limited][2][lane], each lane's W numbers one vector of doubles
    int impulse_base = 0;
    bool enabled = true;
    bool factored = false;  // H of every block factored by an earlier step
    bool refactor = true;   // this step computes and factors H

    explicit Group(const ArticulationView& art) : topo(art) {}
    int links() const { return static_cast<int>(topo.link.size()); }
    int bodies() const { return links() + static_cast<int>(welds.size()); }
    // block b's parameters: its own, or the group's one copy where every world has the same
    const V* block_params_data(int b) const {
      return params.data() + (shared_params ? 0 : static_cast<size_t>(b) * param_size);
    }
    BatchParams<T> block_params(int b) const { return batch_params(topo, block_params_data(b)); }
    // [body][3] each body's own centre of mass (a link's differs from its merged one with welds)
    const V* body_com(int b) const {
      const V* x = block_params_data(b);
      return welds.empty() ? x + links() : x + batch_param_count(topo);
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
  Batches(const Model& model, const std::vector<ArticulationView>& art, const std::vector<std::uint8_t>& batched,
          const std::vector<std::vector<WeldedBody>>& welded, const std::vector<Scalar>& com,
          const std::vector<int>& limit_slot)
      : art_(art), gravity_(model.gravity), slot_(art.size()) {
    std::map<std::vector<double>, int> index;
    for (size_t a = 0; a < art.size(); ++a) {
      if (!batched[a]) continue;
      const auto [it, added] = index.try_emplace(topology_key(art[a], welded[a]), static_cast<int>(groups_.size()));
      if (added) {
        groups_.emplace_back(art[a]);
        for (const WeldedBody& b : welded[a]) {
          Weld w{b.link, {}, {}};
          const T q[4] = {static_cast<T>(b.offset.q.x()), static_cast<T>(b.offset.q.y()),
                          static_cast<T>(b.offset.q.z()), static_cast<T>(b.offset.q.w())};
          std::copy(q, q + 4, w.q);
          for (int m = 0; m < 3; ++m) w.p[m] = static_cast<T>(b.offset.p[m]);
          groups_.back().welds.push_back(w);
        }
      }
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
      for (const int a : G.arts) {
        G.q_off.push_back(art[a].q_begin());
        G.qd_off.push_back(art[a].qd_begin());
        for (int i = 0; i < art[a].link_count(); ++i) G.body.push_back(art[a].body(i));
        for (const WeldedBody& b : welded[a]) G.body.push_back(b.body);
      }
      const int nb = G.bodies();
      // the places from the first world (in the order given where its bodies are not one run); a block is
      // contiguous when each world's bodies keep those places and the worlds follow each other
      const int lowest = *std::min_element(G.body.begin(), G.body.begin() + nb);
      for (int k = 0; k < nb; ++k) G.body_place.push_back(G.body[k] - lowest);
      std::vector<int> places = G.body_place;
      std::sort(places.begin(), places.end());
      bool one_run = true;
      for (int k = 0; k < nb; ++k) one_run &= places[k] == k;
      if (!one_run) std::iota(G.body_place.begin(), G.body_place.end(), 0);
      for (int b = 0; b < G.blocks; ++b) {
        const int* body = &G.body[static_cast<size_t>(b) * W * nb];
        bool contiguous = true;
        for (int l = 0; l < lanes_in(G, b); ++l)
          for (int k = 0; k < nb; ++k)
            contiguous &= body[l * nb + k] == body[0] - G.body_place[0] + l * nb + G.body_place[k];
        G.contiguous.push_back(contiguous);
      }
      const int nv = G.topo.dof_count;
      const ArticulationView& first = art[G.arts[0]];
      for (int i = 0; i < first.link_count(); ++i) {
        const JointType type = first.type(i);
        if (type == JointType::Revolute) G.rotational.push_back(first.qd_start(i));
        if (type == JointType::Ball || type == JointType::Free)
          for (int k = 0; k < 3; ++k) G.rotational.push_back(first.qd_start(i) + k);
      }
      G.param_size = batch_param_count(G.topo) + (G.welds.empty() ? 0 : 3 * G.bodies());
      G.params.resize(static_cast<size_t>(G.blocks) * G.param_size);
      G.H.resize(static_cast<size_t>(G.blocks) * G.topo.packed_size());
      G.S.resize(static_cast<size_t>(G.blocks) * 6 * nv);
      G.origin.resize(static_cast<size_t>(G.blocks) * 3);
      for (int b = 0; b < G.blocks; ++b) gather_params(G, b, com);
      // worlds that do not differ (no domain randomisation) share one copy, which stays in cache
      bool same = true;
      for (int b = 1; b < G.blocks && same; ++b)
        same =
            std::memcmp(&G.params[0], &G.params[static_cast<size_t>(b) * G.param_size], sizeof(V) * G.param_size) == 0;
      if (same) {
        G.params.resize(G.param_size);
        G.params.shrink_to_fit();
        G.shared_params = true;
      }
      for (int k = 0; k < nv; ++k) {
        if (G.topo.coord_of_dof[k] < 0) continue;
        bool finite = false;
        for (const int a : G.arts)
          finite |= std::isfinite(model.joint_limit_lower[art[a].qd_begin() + k]) ||
                    std::isfinite(model.joint_limit_upper[art[a].qd_begin() + k]);
        if (finite) G.limited.push_back(k);
      }
      const int nl = static_cast<int>(G.limited.size());
      G.impulse_base = limit_cell_count_;
      limit_cell_count_ += G.blocks * 2 * nl * W;
      for (int k = 0; k < G.world_count; ++k)
        for (int m = 0; m < nl; ++m) {
          const int slot = limit_slot[art[G.arts[k]].qd_begin() + G.limited[m]];
          if (slot < 0) continue;
          if (static_cast<int>(limit_cell_.size()) < 2 * slot + 2) limit_cell_.resize(2 * slot + 2, -1);
          for (int side = 0; side < 2; ++side)
            limit_cell_[2 * slot + side] = G.impulse_base + (((k / W) * nl + m) * 2 + side) * W + k % W;
        }
      G.limits.resize(static_cast<size_t>(G.blocks) * 2 * nl);
      for (int b = 0; b < G.blocks; ++b)
        for (int m = 0; m < nl; ++m)
          for (int l = 0; l < W; ++l) {
            const int g = art[G.arts[b * W + l]].qd_begin() + G.limited[m];
            G.limits[(b * nl + m) * 2][l] = static_cast<T>(model.joint_limit_lower[g]);
            G.limits[(b * nl + m) * 2 + 1][l] = static_cast<T>(model.joint_limit_upper[g]);
          }
      for (int b = 0; b < G.blocks; ++b) blocks_.push_back({g, b});
    }
    no_skip_.assign(art.size(), 0);
    work_.resize(std::max(1, omp_get_max_threads()));
    std::size_t packed = 0;
    for (const Group& G : groups_) packed = std::max<std::size_t>(packed, G.topo.packed_size());
    lane_factor_.assign(work_.size(), LaneFactor{-1, 0, std::vector<Scalar>(packed)});
    row_work_.resize(work_.size());
    int most_dofs = 0;
    for (const Group& G : groups_) most_dofs = std::max(most_dofs, G.topo.dof_count);
    output_.resize(work_.size());
    for (Output& out : output_) {
      out.S.resize(static_cast<size_t>(6) * most_dofs);
      out.H.resize(packed);
    }
    for (size_t t = 0; t < work_.size(); ++t) {
      work_[t].resize(groups_.size());
      for (size_t g = 0; g < groups_.size(); ++g) {
        work_[t][g].resize(groups_[g].topo);
        work_[t][g].bodies.resize(13 * groups_[g].bodies());
        // every limit row, and four contacts a world, before a step needs more
        const int nl = static_cast<int>(groups_[g].limited.size());
        row_work_[t].resize(2 * nl + 3 * 4, groups_[g].topo.dof_count, 4);
      }
    }
  }

  void enable(int max_dofs) override {
    active_count_ = 0;
    for (Group& G : groups_) {
      G.enabled = G.topo.dof_count < max_dofs;
      if (!G.enabled) G.factored = false;
      if (G.enabled) active_count_ += G.world_count;
    }
  }

  int active_count() const override { return active_count_; }

  const std::vector<int>& limit_cells() const override { return limit_cell_; }
  int limit_cell_count() const override { return limit_cell_count_; }

  bool active(int a) const override { return slot_[a].group >= 0 && groups_[slot_[a].group].enabled; }

  void dynamics(const State& in, const Control& control, const Scalar* tau, Scalar dt_, const DynamicsOptions& options,
                Scalar* qd_out, Scalar* qdd_out, int* factor_failure, int threads) override {
    begin_dynamics(options, threads);
    for_each_block(threads, [&](Group& G, int b, BatchWork<T>& w) {
      dynamics_block(G, b, w, in, control, tau, dt_, options, G.block_H(b), G.block_S(b), &G.origin[3 * b], qd_out,
                     qdd_out, factor_failure, false);
    });
    end_dynamics(true);
  }

  bool solves_rows(int a, const std::uint8_t* skip) const override { return active(a) && !skip[a]; }

  void solve_rows(const State& in, const std::uint8_t* skip, const BlockContacts& bc, const RowSettings& s, Scalar dt_,
                  Scalar* qd_io, Scalar* impulse, int threads) override {
    for_each_block(threads, [&](Group& G, int b, BatchWork<T>& w) {
      rows_block(G, b, w, in, skip, bc, s, dt_, G.block_H(b), G.block_S(b), &G.origin[3 * b], qd_io, impulse, false);
    });
  }

  void integrate(const State& in, Scalar* qd, Scalar dt, Scalar* q_out, const Divergence& divergence,
                 int threads) override {
    for_each_block(threads, [&](Group& G, int b, BatchWork<T>& w) {
      integrate_block(G, b, w, in, qd, dt, q_out, divergence, false);
    });
  }

  void step(const State& in, const Control& control, const Scalar* tau, Scalar dt, const DynamicsOptions& options,
            const BlockContacts* contacts, const RowSettings& rows, Scalar* qd, Scalar* impulse, Scalar* q_out,
            const Divergence& divergence, int* factor_failure, State* out, bool stream, int threads) override {
    begin_dynamics(options, threads);
    for_each_block(
        threads,
        [&](Group& G, int b, BatchWork<T>& w) {
          // in the thread's scratch, not written out to the block: S and o (no scalar row reads them after),
          // and a factor no later step reuses
          Output& scratch = output_[omp_get_thread_num()];
          V* H = !options.keep_factor && G.refactor ? scratch.H.data() : G.block_H(b);
          V *S = scratch.S.data(), *o = scratch.origin;
          dynamics_block(G, b, w, in, control, tau, dt, options, H, S, o, nullptr, nullptr, factor_failure, true);
          if (contacts) rows_block(G, b, w, in, no_skip_.data(), *contacts, rows, dt, H, S, o, qd, impulse, true);
          const IntLanes<T> written =
              integrate_block(G, b, w, in, qd, dt, q_out, divergence, true, factor_failure, out);
          if (out) store_block(G, b, w, w.q_next.data(), written, *out, stream);
        },
        stream_fence);
    end_dynamics(options.keep_factor);
  }

  void store_bodies(const Scalar* q_in, const Scalar* qd_in, State& out, bool stream, int threads) override {
    for_each_block(
        threads,
        [&](Group& G, int b, BatchWork<T>& w) {
          const BatchTopology<T>& topo = G.topo;
          for (int l = 0; l < lanes_in(G, b); ++l) {
            const int q0 = G.q_off[b * W + l], qd0 = G.qd_off[b * W + l];
            copy_few(q_in + q0, topo.coord_count, out.joint_q.data() + q0);
            copy_few(qd_in + qd0, topo.dof_count, out.joint_qd.data() + qd0);
          }
          gather(&G.q_off[b * W], q_in, topo.coord_count, w.q.data());
          gather(&G.qd_off[b * W], qd_in, topo.dof_count, w.qd.data());
          store_block(G, b, w, w.q.data(), ~IntLanes<T>{}, out, stream);
        },
        stream_fence);
  }

  void solve_mass(int a, Scalar* x) const override {
    // rows come a world at a time: its factor is copied out of the block once per step and thread
    const Slot& s = slot_[a];
    const Group& G = groups_[s.group];
    LaneFactor& copy = lane_factor_[omp_get_thread_num()];
    if (copy.articulation != a || copy.step != step_) {
      batch_lane_factor(G.topo, G.block_H(s.block), s.lane, copy.L.data());
      copy.articulation = a;
      copy.step = step_;
    }
    batch_solve_packed(G.topo, copy.L.data(), x);
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
      n += (G.params.size() + G.H.size() + G.S.size() + G.origin.size() + G.limits.size()) * sizeof(V) +
           (G.arts.size() + G.q_off.size() + G.qd_off.size() + G.body.size()) * sizeof(int);
    for (const Group& G : groups_) n += G.contiguous.size();
    n += limit_cell_.size() * sizeof(int);
    for (const LaneFactor& copy : lane_factor_) n += copy.L.size() * sizeof(Scalar);
    for (const Output& out : output_) n += (out.S.size() + out.H.size()) * sizeof(V);
    for (const auto& per_thread : work_)
      for (const BatchWork<T>& w : per_thread)
        for (const auto* v : {&w.Q, &w.p, &w.R, &w.v, &w.a, &w.f, &w.I, &w.vrel, &w.q, &w.qd, &w.x, &w.tau, &w.diag,
                              &w.f_ext, &w.q_next, &w.drive, &w.bodies, &w.IJ})
          n += v->size() * sizeof(V);
    for (const RowWork& R : row_work_)
      n += (R.J.size() + R.z.size() + R.target.size() + R.mu.size() + R.inv_mass.size() + R.lambda.size() +
            R.coef.size() + R.qd_in.size() + R.point.size() + R.frame.size()) *
               sizeof(V) +
           R.active.size() * sizeof(IntLanes<T>) +
           (R.limit_row.size() + R.contact.size() + R.normal.size() + R.nonzero_begin.size() + R.nonzero_end.size()) *
               sizeof(int) +
           R.kind.size() * sizeof(RowKind);
    return n;
  }

 private:
  // worlds in block b that are not padding
  static int lanes_in(const Group& G, int b) { return std::min(W, G.world_count - b * W); }

  void begin_dynamics(const DynamicsOptions& options, int threads) {
    for (Group& G : groups_) G.refactor = options.refactor || !G.factored;
    ++step_;  // factors copied out by solve_mass before are stale
    // one copy per thread of the rows' parallel loop (grows only when the thread count does)
    if (static_cast<int>(lane_factor_.size()) < threads)
      lane_factor_.resize(threads, LaneFactor{-1, 0, lane_factor_[0].L});
  }
  // every block of a group that is on holds its factor for a later step, unless this step made it in
  // scratch (`kept` false) and so left the blocks' own stale
  void end_dynamics(bool kept) {
    for (Group& G : groups_)
      if (G.enabled) G.factored = kept || !G.refactor;
  }

  // one block of dynamics(): FK, bias, H and its factor, the unconstrained velocity into w.qd and qd_out
  // (H, S and o: the block's own, or scratch where nothing after the block's step reads them). With
  // `fused` the block's rows and integration follow in this pass: qd_out is not written
  void dynamics_block(Group& G, int b, BatchWork<T>& w, const State& in, const Control& control, const Scalar* tau,
                      Scalar dt_, const DynamicsOptions& options, V* H, V* S, V* o, Scalar* qd_out, Scalar* qdd_out,
                      int* factor_failure, bool fused) {
    const T dt = static_cast<T>(dt_);
    const BatchTopology<T>& topo = G.topo;
    const int nv = topo.dof_count;
    const int* q_off = &G.q_off[b * W];
    const int* qd_off = &G.qd_off[b * W];
    gather(q_off, in.joint_q.data(), topo.coord_count, w.q.data());
    gather(qd_off, in.joint_qd.data(), nv, w.qd.data());
    const BatchParams<T> P = G.block_params(b);
    batch_kinematics(topo, w.q.data(), w, o);
    batch_subspace(topo, w, o, S);
    batch_velocity(topo, S, w.qd.data(), w);
    batch_link_inertia(topo, P, o, w);
    const V* f_ext = options.wrenches && gather_wrenches(G, b, in.body_f.data(), o, w) ? w.f_ext.data() : nullptr;
    V g[3];
    for (int k = 0; k < 3; ++k) g[k] = V{} + static_cast<T>(gravity_[k]);
    batch_bias(topo, S, g, f_ext, w, w.tau.data());

    // x = tau - bias - damping qd + kd (v_t - qd) - K_s (q_end - q_ref) + ke (q_t - q_end), q_end = q + dt qd
    V* x = w.x.data();
    gather(qd_off, tau, nv, x);
    V* kd = w.drive.data();
    V *vt = kd + nv, *ke = kd + 2 * nv, *qt = kd + 3 * nv;
    if (options.drives) {
      gather(qd_off, control.joint_target_kd.data(), nv, kd);
      gather(qd_off, control.joint_target_vel.data(), nv, vt);
      gather(qd_off, control.joint_target_ke.data(), nv, ke);
      gather(qd_off, control.joint_target_pos.data(), nv, qt);
    } else {
      std::fill(w.drive.begin(), w.drive.end(), V{});
    }
    for (int k = 0; k < nv; ++k) {
      const V qd = w.qd[k];
      x[k] += -w.tau[k] - P.damping[k] * qd + kd[k] * (vt[k] - qd);
      w.diag[k] = dt * (P.damping[k] + kd[k]);
      const int c = topo.coord_of_dof[k];
      if (c < 0) continue;
      const V q_end = w.q[c] + dt * qd;
      x[k] += -P.stiffness[k] * (q_end - P.q_ref[k]) + ke[k] * (qt[k] - q_end);
      w.diag[k] += dt * dt * (P.stiffness[k] + ke[k]);
    }

    IntLanes<T> bad = IntLanes<T>{} - 1;
    if (G.refactor) {
      if (options.tile_gemm)
        batch_mass_matrix_gemm(topo, P, S, w, H);
      else
        batch_mass_matrix(topo, P, S, w, H);
      for (int k = 0; k < nv; ++k) H[topo.row_start[k] + k] += w.diag[k];
      bad = batch_factor(topo, H, options.fuse ? x : nullptr);
      if (options.fuse)
        batch_solve_lower(topo, H, x);
      else
        batch_solve(topo, H, x);
    } else {
      batch_solve(topo, H, x);
    }
    for (int l = 0; l < lanes_in(G, b); ++l) {
      if (bad[l] >= 0) factor_failure[G.arts[b * W + l]] = qd_off[l] + static_cast<int>(bad[l]);
      if (qdd_out)
        for (int k = 0; k < nv; ++k) qdd_out[qd_off[l] + k] = x[k][l];
    }
    if (!qd_out && !fused) return;
    // the new velocities in w.qd, a rotational dof's scaled in double and rounded to T; written to
    // qd_out for the stages after, unless the block steps on (integrate_block writes them once)
    for (int k = 0; k < nv; ++k) w.qd[k] = w.qd[k] + dt * x[k];
    for (const int k : G.rotational) w.qd[k] = scale_in_double(w.qd[k], options.keep);
    if (fused) return;
    for (int l = 0; l < lanes_in(G, b); ++l) {
      Scalar* out = qd_out + qd_off[l];
      for (int k = 0; k < nv; ++k) out[k] = w.qd[k][l];
    }
  }

  // x * s computed in double and rounded to T: what a lane of T stored to a double and scaled becomes
  static V scale_in_double(const V& x, Scalar s) {
    if constexpr (std::is_same_v<T, double>) {
      return x * s;
    } else {
      typedef double Wide __attribute__((vector_size(W * sizeof(double))));
      return __builtin_convertvector(__builtin_convertvector(x, Wide) * s, V);
    }
  }

  // one block of solve_rows()
  // (with `after_dynamics`, w.q and w.qd hold what dynamics_block of this block left, the coordinates and
  // the unconstrained velocities, which are neither gathered from qd_io nor written to it: integrate_block
  // follows and writes the velocities)
  void rows_block(Group& G, int b, BatchWork<T>& w, const State& in, const std::uint8_t* skip, const BlockContacts& bc,
                  const RowSettings& s, Scalar dt_, const V* H, const V* S, const V* o, Scalar* qd_io, Scalar* impulse,
                  bool after_dynamics) {
    const BatchTopology<T>& topo = G.topo;
    const int nl = static_cast<int>(G.limited.size()), nv = topo.dof_count, lanes = lanes_in(G, b);
    const T dt = static_cast<T>(dt_);
    const int* qd_off = &G.qd_off[b * W];
    const int* q_off = &G.q_off[b * W];
    IntLanes<T> mine{};             // lanes solved here: worlds of this block no contact joins to another articulation
    int listed[W] = {}, slots = 0;  // each lane's contacts, their most in a lane
    bool any_mine = false;
    for (int l = 0; l < lanes; ++l) {
      const int a = G.arts[b * W + l];
      if (skip[a]) continue;
      mine[l] = -1;
      any_mine = true;
      listed[l] = bc.start[a + 1] - bc.start[a];
      slots = std::max(slots, listed[l]);
    }
    if (!any_mine || (nl == 0 && slots == 0)) return;
    RowWork& R = row_work_[omp_get_thread_num()];
    R.resize(2 * nl + 3 * slots, nv, slots);
    if (!after_dynamics) gather(qd_off, qd_io, nv, w.qd.data());
    int rows = 0;
    auto add_row = [&](RowKind kind, const IntLanes<T>& on, const V& target, const V& warm) {
      const int r = rows++;
      R.kind[r] = kind;
      R.normal[r] = -1;
      R.active[r] = on;
      R.target[r] = target;
      R.lambda[r] = on ? warm : V{};
      R.mu[r] = V{};
      R.nonzero_begin[r] = nv;
      R.nonzero_end[r] = 0;
      return r;
    };

    // limit rows first, in dof order: J = +-e_k, kept where some lane has the row
    const V* limit = G.limits.data() + static_cast<size_t>(b) * 2 * nl;  // (empty without limits)
    // the block's kept limit impulses, [limited][side] a vector of lanes each (0 where a world has no such limit)
    Scalar* kept = impulse + G.impulse_base + static_cast<size_t>(b) * 2 * nl * W;
    for (int m = 0; m < nl; ++m) {
      const int k = G.limited[m], c = topo.coord_of_dof[k];
      V q = w.q[c];
      if (!after_dynamics)
        for (int l = 0; l < W; ++l) q[l] = static_cast<T>(in.joint_q[q_off[l] + c]);
      for (int side = 0; side < 2; ++side) {
        // gap >= 0 inside the range; the row keeps sign * qd >= target
        const T sign = side == 0 ? 1 : -1;
        const V gap = sign * (q - limit[2 * m + side]);
        const IntLanes<T> finite = lane_abs<T>(limit[2 * m + side]) <= std::numeric_limits<T>::max();
        const IntLanes<T> on = mine & finite & (gap + dt * sign * w.qd[k] < 0);
        R.limit_row[2 * m + side] = -1;
        if (!any_lane<T>(on)) continue;
        const V depth = -gap - T(s.linear_slop);
        const V warm =
            s.use_warmstarting ? T(s.warmstarting_factor) * lanes_from_doubles<T>(kept + (2 * m + side) * W) : V{};
        const int r =
            add_row(RowKind::Unilateral, on, gap >= 0 ? -gap / dt : T(s.erp) * (depth > 0 ? depth : V{}) / dt, warm);
        R.limit_row[2 * m + side] = r;
        V* J = R.J_row(r);
        V* z = R.z_row(r);
        std::fill(J, J + nv, V{});
        J[k] = on ? V{} + sign : V{};
        R.nonzero_begin[r] = k;
        R.nonzero_end[r] = k + 1;
        batch_solve_unit(topo, H, k, z);
        for (int j = 0; j < nv; ++j) z[j] *= sign;
      }
    }

    // contact rows: slot t of lane l is that world's t-th contact, a normal row and two friction rows
    if (slots > 0) gather(qd_off, in.joint_qd.data(), nv, R.qd_in.data());
    const Contacts& C = *bc.contacts;
    for (int t = 0; t < slots; ++t) {
      // each lane's t-th contact, read from the buffer lane by lane
      IntLanes<T> on{};
      V n[3] = {}, p[3] = {}, depth{}, mu{}, restitution{}, previous[3] = {};
      int link[W][2];    // its links (b, a), -1 for static bodies
      int uniform = -1;  // the lane whose links every other lane with a contact shares, if any
      for (int l = 0; l < W; ++l) {
        const int c = t < listed[l] ? bc.list[bc.start[G.arts[b * W + l]] + t] : -1;
        R.contact[t * W + l] = c;
        if (c < 0) continue;
        on[l] = -1;
        for (int m = 0; m < 3; ++m) {
          n[m][l] = static_cast<T>(C.contact_normal[3 * c + m]);
          p[m][l] = static_cast<T>(C.contact_point[3 * c + m] - o[m][l]);
        }
        depth[l] = static_cast<T>(C.contact_depth[c]);
        mu[l] = static_cast<T>(bc.mu[c]);
        restitution[l] = static_cast<T>(bc.restitution[c]);
        if (const Scalar* P = s.use_warmstarting ? C.previous(c) : nullptr)
          for (int m = 0; m < 3; ++m) previous[m][l] = static_cast<T>(P[m]);
        link[l][0] = bc.link_b[c];
        link[l][1] = bc.link_a[c];
        if (uniform == -1) uniform = l;
        if (uniform >= 0 && (link[l][0] != link[uniform][0] || link[l][1] != link[uniform][1])) uniform = -2;
      }
      // coef_k: +1 for the dofs on body b's path, -1 on body a's (the relative velocity is b's point's
      // minus a's), set for all lanes at once where they share their links
      for (int j = 0; j < nv; ++j) R.coef[j] = V{};
      auto add_paths = [&](int l, auto&& add) {
        for (int side = 0; side < 2; ++side) {
          if (link[l][side] < 0) continue;
          for (int e = topo.link_dof_start[link[l][side]]; e < topo.link_dof_start[link[l][side] + 1]; ++e)
            add(topo.link_dofs[e], side == 0 ? T(1) : T(-1));
        }
      };
      if (uniform >= 0) {
        const V one = on ? V{} + 1 : V{};
        add_paths(uniform, [&](int j, T sign) { R.coef[j] += sign * one; });
      } else {
        for (int l = 0; l < W; ++l)
          if (on[l]) add_paths(l, [&](int j, T sign) { R.coef[j][l] += sign; });
      }
      // the normal and two tangents (contact_tangents' frame) in lanes, kept for the impulses written back
      V* d = &R.frame[9 * t];
      lane_tangents<T>(n, d);
      // warm starts: the previous impulse along the new frame (no pull along the normal)
      V warm[3];
      for (int e = 0; e < 3; ++e)
        warm[e] = T(s.warmstarting_factor) *
                  (previous[0] * d[3 * e] + previous[1] * d[3 * e + 1] + previous[2] * d[3 * e + 2]);
      warm[0] = warm[0] > 0 ? warm[0] : V{};
      // normal: push the penetration beyond the slop out at erp / dt, let a gap close in one step,
      // bounce at -restitution times the approach speed above the threshold (a contact that closes
      // within this step)
      V target = depth > T(s.linear_slop) ? T(s.erp) * (depth - T(s.linear_slop)) / dt : (depth < 0 ? depth : V{}) / dt;
      const int first = rows;
      int begin = nv, end = 0;  // the dofs on some lane's paths
      for (int j = 0; j < nv; ++j)
        if (any_lane<T>(R.coef[j] != 0)) {
          begin = std::min(begin, j);
          end = j + 1;
        }
      // u_k = S_lin,k + S_ang,k x p: the velocity of the point p moved by dof k, once for the three rows
      V* u = R.point.data();
      for (int j = 0; j < nv; ++j) {
        const V* s6 = S + 6 * j;
        u[3 * j] = s6[3] + s6[1] * p[2] - s6[2] * p[1];
        u[3 * j + 1] = s6[4] + s6[2] * p[0] - s6[0] * p[2];
        u[3 * j + 2] = s6[5] + s6[0] * p[1] - s6[1] * p[0];
      }
      for (int e = 0; e < 3; ++e) {
        const int r = add_row(e == 0 ? RowKind::Unilateral : RowKind::FrictionPair, on, V{}, warm[e]);
        V* J = R.J_row(r);
        // J_k = coef_k d . u_k: the velocity along d of the point p moved by dof k
        const V* de = d + 3 * e;
        for (int j = 0; j < nv; ++j)
          J[j] = R.coef[j] * (de[0] * u[3 * j] + de[1] * u[3 * j + 1] + de[2] * u[3 * j + 2]);
        std::copy(J, J + nv, R.z_row(r));
        R.normal[r] = first;
        R.nonzero_begin[r] = begin;
        R.nonzero_end[r] = end;
      }
      batch_solve_many(topo, H, end, R.z_row(first), 3, nv);
      V v_approach{};
      for (int j = 0; j < nv; ++j) v_approach += R.J_row(first)[j] * R.qd_in[j];
      const V bounce = -restitution * v_approach;
      const IntLanes<T> closing = (v_approach < -T(s.restitution_threshold)) & (depth - v_approach * dt >= 0);
      R.target[first] = closing & (bounce > target) ? bounce : target;
      R.mu[first + 1] = mu;
    }

    BatchRows<T> batch_rows;
    batch_rows.count = rows;
    batch_rows.dofs = nv;
    batch_rows.kind = R.kind.data();
    batch_rows.normal = R.normal.data();
    batch_rows.J = R.J.data();
    batch_rows.nonzero_begin = R.nonzero_begin.data();
    batch_rows.nonzero_end = R.nonzero_end.data();
    batch_rows.MinvJT = R.z.data();
    batch_rows.target = R.target.data();
    batch_rows.mu = R.mu.data();
    batch_rows.active = R.active.data();
    batch_rows.inv_mass = R.inv_mass.data();
    batch_rows.lambda = R.lambda.data();
    batch_pgs_solve(batch_rows, s.pgs, w.qd.data());

    // velocities and the impulses kept for warm starting: limits per dof and side (0 where its row is off
    // or not finite), contacts as world vectors on body b
    for (int m = 0; m < 2 * nl; ++m) {
      const int r = R.limit_row[m];
      const V x = r >= 0 ? (R.active[r] ? R.lambda[r] : V{}) : V{};
      doubles_from_lanes<T>(lane_abs<T>(x) <= std::numeric_limits<T>::max() ? x : V{}, mine, kept + m * W);
    }
    if (!after_dynamics) scatter(qd_off, w.qd.data(), nv, mine, qd_io);
    for (int t = 0; t < slots; ++t) {
      const V* d = &R.frame[9 * t];
      const V* lambda = &R.lambda[rows - 3 * (slots - t)];
      V P[3];
      for (int m = 0; m < 3; ++m) P[m] = lambda[0] * d[m] + lambda[1] * d[3 + m] + lambda[2] * d[6 + m];
      IntLanes<T> finite = ~IntLanes<T>{};
      for (int m = 0; m < 3; ++m) finite &= lane_abs<T>(P[m]) <= std::numeric_limits<T>::max();
      for (int l = 0; l < W; ++l) {
        const int c = R.contact[t * W + l];
        if (c < 0) continue;
        for (int m = 0; m < 3; ++m) bc.contacts->contact_impulse[3 * c + m] = finite[l] ? P[m][l] : 0;
      }
    }
  }

  // body_q and body_qd of block b's worlds where `written` has their lane, from the coordinates q and the
  // velocities w.qd (lanes): the kinematics in the thread's scratch (the block's own o stays that of the
  // step; the motion subspaces are not written out). With `stream`, a block whose worlds' bodies follow
  // each other, all written, is written around the caches
  void store_block(Group& G, int b, BatchWork<T>& w, const V* q, const IntLanes<T>& written, State& out, bool stream) {
    const BatchTopology<T>& topo = G.topo;
    V* o = output_[omp_get_thread_num()].origin;
    batch_kinematics(topo, q, w, o);
    batch_subspace_velocity(topo, o, w.qd.data(), w);
    const int n = G.links(), nb = G.bodies(), lanes = lanes_in(G, b);
    const int* body = &G.body[static_cast<size_t>(b) * W * nb];
    // body_q = [p, Q]; body_qd = [velocity of the centre of mass, angular velocity], world frame:
    // in lanes first, every body's body_q then every body's body_qd, each body at its place (a world's
    // rows of each array in the model's order when its bodies are one run), then written out world by world
    V* x_q = w.bodies.data();
    V* x_qd = x_q + 7 * nb;
    auto put = [&](int k, const V* p, const V* Q, const V* com, const V* v) {
      V* x = x_q + 7 * k;
      V* y = x_qd + 6 * k;
      V c[3];
      mat_vec(p, Q, com, o, c);
      for (int m = 0; m < 3; ++m) x[m] = p[m];
      for (int m = 0; m < 4; ++m) x[3 + m] = Q[m];
      y[0] = v[3] + v[1] * c[2] - v[2] * c[1];
      y[1] = v[4] + v[2] * c[0] - v[0] * c[2];
      y[2] = v[5] + v[0] * c[1] - v[1] * c[0];
      for (int m = 0; m < 3; ++m) y[3 + m] = v[m];
    };
    const V* body_com = G.body_com(b);
    const int* place = G.body_place.data();
    for (int i = 0; i < n; ++i) put(place[i], &w.p[3 * i], &w.Q[4 * i], body_com + 3 * i, &w.v[6 * i]);
    for (size_t k = 0; k < G.welds.size(); ++k) {
      const Weld& weld = G.welds[k];
      V p[3], Q[4], d[3];
      const V* R = &w.R[9 * weld.link];
      for (int m = 0; m < 3; ++m) d[m] = R[3 * m] * weld.p[0] + R[3 * m + 1] * weld.p[1] + R[3 * m + 2] * weld.p[2];
      for (int m = 0; m < 3; ++m) p[m] = w.p[3 * weld.link + m] + d[m];
      quat_product(&w.Q[4 * weld.link], weld.q, Q);
      put(place[n + k], p, Q, body_com + 3 * (n + k), &w.v[6 * weld.link]);
    }
    IntLanes<T> real{};
    for (int l = 0; l < lanes; ++l) real[l] = -1;
    const IntLanes<T> store = written & real;
    bool all = true;
    for (int l = 0; l < lanes; ++l) all &= written[l] != 0;
    if (G.contiguous[b]) {
      // the block's worlds' bodies follow each other: each world's rows of body_q, then of body_qd, are
      // written at once, with `stream` (and every lane written) around the caches
      auto write = [&](const V* x, int width, std::vector<Scalar>& field) {
        Scalar* first = field.data() + width * (body[0] - place[0]);
        if (stream && all) {
          stream_rows_from_lanes<T>(x, width * nb, lanes, first);
          return;
        }
        Scalar* rows[W];
        for (int l = 0; l < W; ++l) rows[l] = first + width * nb * (l < lanes ? l : 0);
        rows_from_lanes<T>(x, width * nb, store, rows);
      };
      write(x_q, 7, out.body_q);
      write(x_qd, 6, out.body_qd);
      return;
    }
    for (int l = 0; l < lanes; ++l)
      for (int k = 0; k < nb && written[l]; ++k) {
        Scalar* q = out.body_q.data() + 7 * body[l * nb + k];
        Scalar* qd = out.body_qd.data() + 6 * body[l * nb + k];
        for (int m = 0; m < 7; ++m) q[m] = x_q[7 * place[k] + m][l];
        for (int m = 0; m < 6; ++m) qd[m] = x_qd[6 * place[k] + m][l];
      }
  }

  // one block of integrate(); the velocities written to qd. With `out` (a step that stores as it goes),
  // the coordinates and velocities are written to out.joint_q and out.joint_qd instead, and only for the
  // worlds that did not diverge and whose factor did not fail (the lanes returned); q_out and qd are not
  // written
  // (with `after_rows`, w.q and w.qd hold the coordinates and the velocities the block's dynamics and rows
  // left in this pass: not gathered)
  IntLanes<T> integrate_block(Group& G, int b, BatchWork<T>& w, const State& in, Scalar* qd, Scalar dt, Scalar* q_out,
                              const Divergence& divergence, bool after_rows, const int* factor_failure = nullptr,
                              State* out = nullptr) {
    const int nq = G.topo.coord_count, nv = G.topo.dof_count;
    if (!after_rows) {
      gather(&G.q_off[b * W], in.joint_q.data(), nq, w.q.data());
      gather(&G.qd_off[b * W], qd, nv, w.qd.data());
    }
    batch_integrate(G.topo, w.q.data(), w.qd.data(), static_cast<T>(dt), w.q_next.data());
    // the guard on the lanes: every entry finite (|x| <= max is false for inf and NaN), then the
    // fastest dof against the speed in double, where the solver's guard compares
    IntLanes<T> finite = ~IntLanes<T>{};
    V fastest{};
    for (int k = 0; k < nq; ++k) finite &= lane_abs<T>(w.q_next[k]) <= std::numeric_limits<T>::max();
    for (int k = 0; k < nv; ++k) {
      const V speed = lane_abs<T>(w.qd[k]);
      finite &= speed <= std::numeric_limits<T>::max();
      fastest = speed > fastest ? speed : fastest;
    }
    IntLanes<T> written{};
    for (int l = 0; l < lanes_in(G, b); ++l) {
      const int a = G.arts[b * W + l];
      const bool diverged = !finite[l] || static_cast<Scalar>(fastest[l]) > divergence.speed;
      divergence.diverged[a] = diverged;
      if (out && (diverged || factor_failure[a] >= 0)) continue;
      written[l] = -1;
    }
    scatter(&G.q_off[b * W], w.q_next.data(), nq, written, out ? out->joint_q.data() : q_out);
    scatter(&G.qd_off[b * W], w.qd.data(), nv, written, out ? out->joint_qd.data() : qd);
    return written;
  }

  // dst[0, n) = src[0, n), the few numbers of one world: in registers, eight at a time with the last
  // eight overlapping (a call to memmove took longer than the copy)
  static void copy_few(const Scalar* src, int n, Scalar* dst) {
    if (n < 8) {
      std::copy_n(src, n, dst);
      return;
    }
    for (int k = 0; k + 8 < n; k += 8) std::memcpy(dst + k, src + k, 8 * sizeof(Scalar));
    std::memcpy(dst + n - 8, src + n - 8, 8 * sizeof(Scalar));
  }

  // out[k][l] = field[off[l] + k]
  static void gather(const int* off, const Scalar* field, int count, V* out) {
    const Scalar* row[W];
    for (int l = 0; l < W; ++l) row[l] = field + off[l];
    lanes_from_rows<T>(row, count, out);
  }
  // field[off[l] + k] = in[k][l] for the lanes l set in `lanes`
  static void scatter(const int* off, const V* in, int count, const IntLanes<T>& lanes, Scalar* field) {
    Scalar* row[W];
    for (int l = 0; l < W; ++l) row[l] = field + off[l];
    rows_from_lanes<T>(in, count, lanes, row);
  }

  // c = R(Q) com + p - o
  static void mat_vec(const V* p, const V* Q, const V* com, const V* o, V* c) {
    const V tx = 2 * (Q[1] * com[2] - Q[2] * com[1]), ty = 2 * (Q[2] * com[0] - Q[0] * com[2]),
            tz = 2 * (Q[0] * com[1] - Q[1] * com[0]);
    c[0] = com[0] + Q[3] * tx + Q[1] * tz - Q[2] * ty + p[0] - o[0];
    c[1] = com[1] + Q[3] * ty + Q[2] * tx - Q[0] * tz + p[1] - o[1];
    c[2] = com[2] + Q[3] * tz + Q[0] * ty - Q[1] * tx + p[2] - o[2];
  }

  static void quat_product(const V* a, const T* b, V* out) {
    out[0] = a[3] * b[0] + a[0] * b[3] + a[1] * b[2] - a[2] * b[1];
    out[1] = a[3] * b[1] - a[0] * b[2] + a[1] * b[3] + a[2] * b[0];
    out[2] = a[3] * b[2] + a[0] * b[1] - a[1] * b[0] + a[2] * b[3];
    out[3] = a[3] * b[3] - a[0] * b[0] - a[1] * b[1] - a[2] * b[2];
  }

  void gather_params(Group& G, int b, const std::vector<Scalar>& com) {
    const int nb = G.bodies();
    V* x = G.params.data() + static_cast<size_t>(b) * G.param_size;
    V* own_com = x + batch_param_count(G.topo);  // with welded bodies: every body's own centre of mass
    for (int l = 0; l < W; ++l) {
      batch_set_params(G.topo, art_[G.arts[b * W + l]], l, x);
      const int* body = &G.body[static_cast<size_t>(b * W + l) * nb];
      if (!G.welds.empty())
        for (int k = 0; k < nb; ++k)
          for (int m = 0; m < 3; ++m) own_com[3 * k + m][l] = static_cast<T>(com[3 * body[k] + m]);
    }
  }

  // applied wrenches [f at the centre of mass; torque] of the block's bodies (welded ones onto their
  // links) as spatial forces about o; false when the block has none
  bool gather_wrenches(const Group& G, int b, const Scalar* body_f, const V* o, BatchWork<T>& w) const {
    const int n = G.links(), nb = G.bodies();
    const int* body = &G.body[static_cast<size_t>(b) * W * nb];
    bool any = false;
    for (int k = 0; k < W * nb; ++k)
      for (int m = 0; m < 6; ++m) any |= body_f[6 * body[k] + m] != 0;
    if (!any) return false;
    std::fill(w.f_ext.begin(), w.f_ext.end(), V{});
    const V* body_com = G.body_com(b);
    for (int k = 0; k < nb; ++k) {
      const int link = k < n ? k : G.welds[k - n].link;
      V f[6], c[3], p[3], Q[4];
      for (int l = 0; l < W; ++l)
        for (int m = 0; m < 6; ++m) f[m][l] = static_cast<T>(body_f[6 * body[l * nb + k] + m]);
      if (k < n) {
        mat_vec(&w.p[3 * k], &w.Q[4 * k], body_com + 3 * k, o, c);
      } else {
        const Weld& weld = G.welds[k - n];
        const V* R = &w.R[9 * link];
        for (int m = 0; m < 3; ++m)
          p[m] = w.p[3 * link + m] + R[3 * m] * weld.p[0] + R[3 * m + 1] * weld.p[1] + R[3 * m + 2] * weld.p[2];
        quat_product(&w.Q[4 * link], weld.q, Q);
        mat_vec(p, Q, body_com + 3 * k, o, c);
      }
      // torque about o: t + (c - o) x f
      V* F = &w.f_ext[6 * link];
      F[0] += f[3] + c[1] * f[2] - c[2] * f[1];
      F[1] += f[4] + c[2] * f[0] - c[0] * f[2];
      F[2] += f[5] + c[0] * f[1] - c[1] * f[0];
      for (int m = 0; m < 3; ++m) F[3 + m] += f[m];
    }
    return true;
  }

  template <typename F>
  void for_each_block(int threads, F&& f) {
    for_each_block(threads, f, [] {});
  }
  // ... then done() once on each thread
  template <typename F, typename Done>
  void for_each_block(int threads, F&& f, Done&& done) {
    const int count = static_cast<int>(blocks_.size());
    // no more threads than blocks: a team with idle members still pays for waking them at every call
    const int n =
        std::min({threads > 0 ? threads : static_cast<int>(work_.size()), static_cast<int>(work_.size()), count});
    // float32 blocks flush subnormals (see SubnormalsAsZero), the mode set once on each thread: setting it
    // around each block cost 1.5 % of the contact-free quadruped's float32 step at 4096 worlds
    using Flush = std::conditional_t<std::is_same_v<T, float>, SubnormalsAsZero, NoScope>;
    parallel_for<Flush>(
        n, count,
        [&](int k) {
          Group& G = groups_[blocks_[k].first];
          if (G.enabled) f(G, blocks_[k].second, work_[omp_get_thread_num()][blocks_[k].first]);
        },
        done);
  }

  // a thread's rows of one block (solve_rows); grows to the most rows a block has had. On cache lines of
  // its own, as LaneFactor: each block writes `dofs`
  struct alignas(64) RowWork {
    int dofs = 0;
    std::vector<RowKind> kind;
    std::vector<int> normal;
    std::vector<int> nonzero_begin, nonzero_end;  // [row]: where J may be nonzero
    std::vector<IntLanes<T>> active;
    std::vector<V> J, z, target, mu, inv_mass, lambda;  // [row][dof] J and M^-1 J^T, then [row]
    std::vector<int> limit_row;                         // [limited][2] its row, or -1
    std::vector<int> contact;                           // [slot][lane] the contact, or -1
    std::vector<V> frame;                               // [slot][3][3] the normal and tangents
    std::vector<V> coef, qd_in;                         // [dof] a slot's +-1 per dof on a contact's paths; in.joint_qd
    std::vector<V> point;  // [dof][3] the velocity of a slot's contact point moved by each dof
    void resize(int rows, int dofs_, int slots) {
      dofs = dofs_;
      if (static_cast<int>(kind.size()) < rows) {
        kind.resize(rows);
        normal.resize(rows);
        active.resize(rows);
        for (auto* x : {&target, &mu, &inv_mass, &lambda}) x->resize(rows);
      }
      for (auto* x : {&J, &z})
        if (x->size() < static_cast<size_t>(rows) * dofs) x->resize(static_cast<size_t>(rows) * dofs);
      for (auto* x : {&nonzero_begin, &nonzero_end})
        if (static_cast<int>(x->size()) < rows) x->resize(rows);
      if (limit_row.size() < static_cast<size_t>(rows)) limit_row.resize(rows);
      if (contact.size() < static_cast<size_t>(slots) * W) contact.resize(static_cast<size_t>(slots) * W);
      if (frame.size() < static_cast<size_t>(slots) * 9) frame.resize(static_cast<size_t>(slots) * 9);
      for (auto* x : {&coef, &qd_in})
        if (static_cast<int>(x->size()) < dofs) x->resize(dofs);
      if (static_cast<int>(point.size()) < 3 * dofs) point.resize(3 * dofs);
    }
    V* J_row(int r) { return J.data() + static_cast<size_t>(r) * dofs; }
    V* z_row(int r) { return z.data() + static_cast<size_t>(r) * dofs; }
  };

  // a world's factor copied out of its block (solve_mass), per thread
  struct alignas(64) LaneFactor {
    int articulation = -1;
    std::uint64_t step = 0;
    std::vector<Scalar> L;
  };

  const std::vector<ArticulationView>& art_;
  Vec3 gravity_;
  std::uint64_t step_ = 0;  // dynamics calls so far
  mutable std::vector<LaneFactor> lane_factor_;
  std::vector<Group> groups_;
  std::vector<std::pair<int, int>> blocks_;  // (group, block) in order
  std::vector<Slot> slot_;                   // per articulation
  // per thread: store_bodies' scratch (its S and o), also step()'s S and o, and the factor step() makes
  // where no later step reuses it
  struct Output {
    std::vector<V> S, H;
    V origin[3];
  };
  std::vector<Output> output_;
  int active_count_ = 0;         // articulations in groups that are on
  std::vector<int> limit_cell_;  // [2 * limit slot + side] (limit_cells)
  int limit_cell_count_ = 0;
  std::vector<std::uint8_t> no_skip_;            // per articulation: 0, step()'s skip for solve_rows
  std::vector<std::vector<BatchWork<T>>> work_;  // per thread, per group
  std::vector<RowWork> row_work_;                // per thread
};

}  // namespace

std::unique_ptr<ArticulationBatches> ArticulationBatches::make(
    const Model& model, const std::vector<ArticulationView>& art, const std::vector<std::uint8_t>& batched,
    const std::vector<std::vector<WeldedBody>>& welded, const std::vector<Scalar>& com,
    const std::vector<int>& limit_slot, Precision precision) {
  if (precision == Precision::Float32)
    return std::make_unique<Batches<float>>(model, art, batched, welded, com, limit_slot);
  return std::make_unique<Batches<double>>(model, art, batched, welded, com, limit_slot);
}

}  // namespace novaphy
