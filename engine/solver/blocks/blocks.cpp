// The blocks route (engine/solver/blocks/blocks.h): the batches laid out in blocks of lanes, and each
// unit (a block) run through the stages of engine/solver/blocks/block_data.h on its thread's scratch.
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <numeric>

#include "engine/solver/blocks/block_data.h"
#include "engine/solver/parts/rows.h"
#include "engine/threads/parallel.h"

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
  struct Slot {
    int group = -1, block = 0, lane = 0;
  };

 public:
  Batches(const Model& model, const std::vector<ArticulationView>& art, const std::vector<std::uint8_t>& batched,
          const std::vector<std::vector<WeldedBody>>& welded, const std::vector<Scalar>& com,
          const std::vector<int>& limit_slot)
      : art_(art), slot_(art.size()) {
    group_articulations(batched, welded);
    for (int g = 0; g < static_cast<int>(groups_.size()); ++g) {
      lay_out(groups_[g], g, welded);
      gather_params(groups_[g], com);
      lay_out_limits(groups_[g], model, limit_slot);
      lay_out_friction(groups_[g], model);
    }
    size_scratch();
    enable(std::numeric_limits<int>::max());
  }

  void read_parameters(const Model& model, const std::vector<Scalar>& com, const std::vector<std::uint8_t>& changed,
                       int threads) override {
    bool more_rows = false;
    for (BatchGroup<T>& G : groups_) {
      bool any = false;
      for (const int a : G.arts) any |= changed[a] != 0;
      if (!any) continue;
      if (G.shared_params) {  // one copy for every block no more
        G.params.resize(static_cast<size_t>(G.blocks) * G.param_size);
        for (int b = 1; b < G.blocks; ++b)
          std::copy_n(G.params.begin(), G.param_size, G.params.begin() + static_cast<size_t>(b) * G.param_size);
        G.shared_params = false;
      }
      // a changed lane's parameters and dry friction; dry friction on a dof that had none in any world: the group's
      // friction rows laid out again
      const int nf = static_cast<int>(G.frictional.size());
      std::vector<std::uint8_t> gains(G.blocks, 0);  // per block: a dof that gains dry friction
      parallel_for(std::clamp(threads, 1, G.blocks), G.blocks, [&](int b) {
        for (int l = 0; l < W; ++l) {
          const int a = G.arts[b * W + l];
          if (!changed[a]) continue;
          set_lane_params(G, b, l, com);
          const Scalar* loss = model.joint_frictionloss.data() + art_[a].qd_begin();
          for (int m = 0; m < nf; ++m) G.frictionloss[b * nf + m][l] = static_cast<T>(loss[G.frictional[m]]);
          for (int k = 0; k < G.topo.dof_count; ++k)
            gains[b] |= loss[k] > 0 && std::find(G.frictional.begin(), G.frictional.end(), k) == G.frictional.end();
        }
      });
      const bool more = std::find(gains.begin(), gains.end(), 1) != gains.end();
      if (more) lay_out_friction(G, model);
      more_rows |= more;
    }
    if (more_rows) size_scratch();
  }

  void enable(int max_dofs) override {
    units_.clear();
    for (int g = 0; g < static_cast<int>(groups_.size()); ++g) {
      BatchGroup<T>& G = groups_[g];
      G.enabled = G.topo.dof_count < max_dofs;
      if (!G.enabled) G.factored = false;
      if (!G.enabled) continue;
      for (int b = 0; b < G.blocks; ++b) units_.push_back({g, b});
    }
  }
  bool active(int a) const override { return slot_[a].group >= 0 && groups_[slot_[a].group].enabled; }
  const std::vector<int>& limit_cells() const override { return limit_cell_; }
  int limit_cell_count() const override { return limit_cell_count_; }
  int unit_count() const override { return static_cast<int>(units_.size()); }
  int unit_articulations(int unit, int* out) const override {
    const auto [g, b] = units_[unit];
    const BatchGroup<T>& G = groups_[g];
    const int lanes = G.lanes_in(b);
    std::copy_n(&G.arts[static_cast<size_t>(b) * kLanes<T>], lanes, out);
    return lanes;
  }
  int group_count() const override { return static_cast<int>(groups_.size()); }
  int block_count() const override {
    int n = 0;
    for (const BatchGroup<T>& G : groups_) n += G.blocks;
    return n;
  }
  int lanes() const override { return W; }

  void begin_step(const StepContext& step) override {
    for (BatchGroup<T>& G : groups_) G.refactor = step.refactor || !G.factored;
    ++step_;  // factors copied out by solve_mass before are stale
    for (ThreadScratch<T>& s : scratch_) s.phases = {};
  }
  // every block of a group that is on holds its factor for a later step, unless this step made it in
  // scratch and so left the blocks' own stale
  void end_step(const StepContext& step) override {
    for (BatchGroup<T>& G : groups_)
      if (G.enabled) G.factored = !G.refactor || step.keep_factor() || step.split;
  }

  void dynamics(const UnitPass& pass, const StepContext& step, const UnitInputs& inputs) override {
    const auto [g, b] = units_[pass.unit];
    ThreadScratch<T>& scratch = scratch_[omp_get_thread_num()];
    block_dynamics(groups_[g], b, kinematics(pass, scratch, step), step, inputs, scratch.work[g],
                   pass.carry_on(Stage::Dynamics));
  }
  void rows(const UnitPass& pass, const StepContext& step) override {
    const auto [g, b] = units_[pass.unit];
    ThreadScratch<T>& scratch = scratch_[omp_get_thread_num()];
    block_rows<T>(groups_[g], b, kinematics(pass, scratch, step), step, scratch.work[g], scratch.rows,
                  pass.carried(Stage::Rows), pass.carry_on(Stage::Rows),
                  step.settings.profile_stages ? &scratch.phases : nullptr);
  }
  void integrate(const UnitPass& pass, const StepContext& step) override {
    const auto [g, b] = units_[pass.unit];
    ThreadScratch<T>& scratch = scratch_[omp_get_thread_num()];
    scratch.written = block_integrate(groups_[g], b, step, scratch.work[g], pass.carried(Stage::Integrate),
                                      pass.carry_on(Stage::Integrate));
  }
  // from this pass's Integrate (its written lanes) or from the step's vectors
  void store(const UnitPass& pass, const StepContext& step) override {
    const auto [g, b] = units_[pass.unit];
    BatchGroup<T>& G = groups_[g];
    ThreadScratch<T>& scratch = scratch_[omp_get_thread_num()];
    BatchWork<T>& w = scratch.work[g];
    const BatchTopology<T>& topo = G.topo;
    if (!pass.carried(Stage::Store)) {
      scratch.written = IntLanes<T>{};
      for (int l = 0; l < G.lanes_in(b); ++l) {
        const int a = G.arts[b * W + l], q0 = G.q_off[b * W + l], qd0 = G.qd_off[b * W + l];
        if (step.diverged[a] || step.factor_failure[a] >= 0) continue;
        scratch.written[l] = -1;
        std::copy_n(step.q_next + q0, topo.coord_count, step.out->joint_q.data() + q0);
        std::copy_n(step.qd + qd0, topo.dof_count, step.out->joint_qd.data() + qd0);
      }
      gather_lanes<T>(&G.q_off[b * W], step.q_next, topo.coord_count, w.q_next.data());
      gather_lanes<T>(&G.qd_off[b * W], step.qd, topo.dof_count, w.qd.data());
    }
    block_store(G, b, w, scratch.origin, w.q_next.data(), scratch.written, *step.out, step.stream);
  }

  void accelerations(const State& in, const Control& control, const Scalar* tau, const Scalar* body_f, bool wrenches,
                     Scalar* qdd, int* factor_failure) override {
    StepContext step;
    step.in = &in;
    step.control = &control;
    step.tau = tau;
    step.body_f = body_f;
    step.factor_failure = factor_failure;
    step.split = true;
    UnitInputs inputs;
    inputs.wrenches = wrenches;
    begin_step(step);
    ThreadScratch<T>& scratch = scratch_[0];
    for (const auto& [g, b] : units_) {
      BatchGroup<T>& G = groups_[g];
      const BlockKinematics<T> kin{G.block_H(b), G.block_S(b), &G.origin[3 * b]};
      block_dynamics(G, b, kin, step, inputs, scratch.work[g], false, qdd);
    }
    end_step(step);
  }

  RowPhaseSeconds row_phases() const override {
    RowPhaseSeconds sum;
    for (const ThreadScratch<T>& s : scratch_) {
      sum.limits += s.phases.limits;
      sum.contacts += s.phases.contacts;
      sum.sweeps += s.phases.sweeps;
    }
    return sum;
  }

  void solve_mass(int a, Scalar* x) override {
    // rows come a world at a time: its factor is copied out of the block once per step and thread
    const Slot& s = slot_[a];
    const BatchGroup<T>& G = groups_[s.group];
    ThreadScratch<T>& scratch = scratch_[omp_get_thread_num()];
    if (scratch.factor_of != a || scratch.factor_step != step_) {
      batch_lane_factor(G.topo, G.block_H(s.block), s.lane, scratch.factor.data());
      scratch.factor_of = a;
      scratch.factor_step = step_;
    }
    batch_solve_packed(G.topo, scratch.factor.data(), x);
  }

  void point_jacobian(int a, int link, const Vec3* p, const Vec3& d, Scalar sign, Scalar* J) const override {
    const Slot& s = slot_[a];
    const BatchGroup<T>& G = groups_[s.group];
    const V* S = G.block_S(s.block);
    const V* o = &G.origin[3 * s.block];
    const Vec3 r = p ? Vec3(p->x() - o[0][s.lane], p->y() - o[1][s.lane], p->z() - o[2][s.lane]) : Vec3::Zero();
    const auto& topo = G.topo;
    for (int i = link; i >= 0; i = topo.link[i].parent)
      for (int k = topo.link[i].qd_start; k < topo.link[i].qd_start + topo.link[i].dof; ++k) {
        Scalar s6[6];
        for (int m = 0; m < 6; ++m) s6[m] = S[6 * k + m][s.lane];
        J[k] += sign * motion_along(s6, p ? r.data() : nullptr, d.data());
      }
  }

  std::size_t bytes() const override {
    std::size_t n = limit_cell_.size() * sizeof(int);
    for (const BatchGroup<T>& G : groups_)
      n += (G.params.size() + G.H.size() + G.S.size() + G.origin.size() + G.limits.size() + G.frictionloss.size()) *
               sizeof(V) +
           (G.arts.size() + G.q_off.size() + G.qd_off.size() + G.body.size()) * sizeof(int) + G.contiguous.size() +
           (G.limit_softness.size() + G.friction_softness.size()) * sizeof(Softness) +
           (G.limit_soft.size() + G.friction_soft.size()) * sizeof(IntLanes<T>);
    for (const ThreadScratch<T>& s : scratch_) {
      n += (s.S.size() + s.H.size()) * sizeof(V) + s.factor.size() * sizeof(Scalar) + s.rows.bytes();
      for (const BatchWork<T>& w : s.work) n += w.bytes();
    }
    return n;
  }

 private:
  // where the block of pass.unit keeps its H, S and o this step: a thread's scratch when the pass takes the block
  // from its dynamics through its rows and nothing after it reads them (a factor no later step reuses), else the
  // block's own storage
  BlockKinematics<T> kinematics(const UnitPass& pass, ThreadScratch<T>& scratch, const StepContext& step) {
    const auto [g, b] = units_[pass.unit];
    BatchGroup<T>& G = groups_[g];
    const bool in_pass = !step.split && pass.runs(Stage::Dynamics) && pass.runs(Stage::Rows);
    if (!in_pass) return {G.block_H(b), G.block_S(b), &G.origin[3 * b]};
    V* H = !step.keep_factor() && G.refactor ? scratch.H.data() : G.block_H(b);
    return {H, scratch.S.data(), scratch.origin};
  }

  void group_articulations(const std::vector<std::uint8_t>& batched,
                           const std::vector<std::vector<WeldedBody>>& welded) {
    std::map<std::vector<double>, int> index;
    for (size_t a = 0; a < art_.size(); ++a) {
      if (!batched[a]) continue;
      const auto [it, added] = index.try_emplace(topology_key(art_[a], welded[a]), static_cast<int>(groups_.size()));
      if (added) {
        groups_.emplace_back(art_[a]);
        for (const WeldedBody& b : welded[a]) {
          typename BatchGroup<T>::Weld w{b.link, {}, {}};
          const T q[4] = {static_cast<T>(b.offset.q.x()), static_cast<T>(b.offset.q.y()),
                          static_cast<T>(b.offset.q.z()), static_cast<T>(b.offset.q.w())};
          std::copy(q, q + 4, w.q);
          for (int m = 0; m < 3; ++m) w.p[m] = static_cast<T>(b.offset.p[m]);
          groups_.back().welds.push_back(w);
        }
      }
      groups_[it->second].arts.push_back(static_cast<int>(a));
    }
  }

  // slots, coordinates, bodies and their places, rotational dofs of group g
  void lay_out(BatchGroup<T>& G, int g, const std::vector<std::vector<WeldedBody>>& welded) {
    G.world_count = static_cast<int>(G.arts.size());
    G.blocks = (G.world_count + W - 1) / W;
    for (int k = 0; k < G.world_count; ++k) slot_[G.arts[k]] = {g, k / W, k % W};
    G.arts.resize(static_cast<size_t>(G.blocks) * W, -1);
    for (int b = 0; b < G.blocks; ++b)
      for (int l = 0; l < W; ++l)
        if (G.arts[b * W + l] < 0) G.arts[b * W + l] = G.arts[b * W];
    for (const int a : G.arts) {
      G.q_off.push_back(art_[a].q_begin());
      G.qd_off.push_back(art_[a].qd_begin());
      for (int i = 0; i < art_[a].link_count(); ++i) G.body.push_back(art_[a].body(i));
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
      for (int l = 0; l < G.lanes_in(b); ++l)
        for (int k = 0; k < nb; ++k)
          contiguous &= body[l * nb + k] == body[0] - G.body_place[0] + l * nb + G.body_place[k];
      G.contiguous.push_back(contiguous);
    }
    const ArticulationView& first = art_[G.arts[0]];
    for (int i = 0; i < first.link_count(); ++i) {
      const JointType type = first.type(i);
      if (type == JointType::Revolute) G.rotational.push_back(first.qd_start(i));
      if (type == JointType::Ball || type == JointType::Free)
        for (int k = 0; k < 3; ++k) G.rotational.push_back(first.qd_start(i) + k);
    }
  }

  // block b's lane l's parameters from its articulation's model arrays (and with welded bodies every body's own
  // centre of mass from com)
  void set_lane_params(BatchGroup<T>& G, int b, int l, const std::vector<Scalar>& com) {
    const int nb = G.bodies();
    V* x = G.params.data() + static_cast<size_t>(b) * G.param_size;
    batch_set_params(G.topo, art_[G.arts[b * W + l]], l, x);
    if (G.welds.empty()) return;
    V* own_com = x + batch_param_count(G.topo);
    const int* body = &G.body[static_cast<size_t>(b * W + l) * nb];
    for (int k = 0; k < nb; ++k)
      for (int m = 0; m < 3; ++m) own_com[3 * k + m][l] = static_cast<T>(com[3 * body[k] + m]);
  }

  // every block's parameters; worlds that do not differ (no domain randomisation) share one copy
  void gather_params(BatchGroup<T>& G, const std::vector<Scalar>& com) {
    const int nb = G.bodies();
    G.param_size = batch_param_count(G.topo) + (G.welds.empty() ? 0 : 3 * nb);
    G.params.resize(static_cast<size_t>(G.blocks) * G.param_size);
    G.H.resize(static_cast<size_t>(G.blocks) * G.topo.packed_size());
    G.S.resize(static_cast<size_t>(G.blocks) * 6 * G.topo.dof_count);
    G.origin.resize(static_cast<size_t>(G.blocks) * 3);
    for (int b = 0; b < G.blocks; ++b)
      for (int l = 0; l < W; ++l) set_lane_params(G, b, l, com);
    bool same = true;
    for (int b = 1; b < G.blocks && same; ++b)
      same = std::memcmp(&G.params[0], &G.params[static_cast<size_t>(b) * G.param_size], sizeof(V) * G.param_size) == 0;
    if (!same) return;
    G.params.resize(G.param_size);
    G.params.shrink_to_fit();
    G.shared_params = true;
  }

  // the group's limited dofs, its blocks' limits, and the cells of their kept impulses
  void lay_out_limits(BatchGroup<T>& G, const Model& model, const std::vector<int>& limit_slot) {
    for (int k = 0; k < G.topo.dof_count; ++k) {
      if (G.topo.coord_of_dof[k] < 0) continue;
      bool finite = false;
      for (const int a : G.arts)
        finite |= std::isfinite(model.joint_limit_lower[art_[a].qd_begin() + k]) ||
                  std::isfinite(model.joint_limit_upper[art_[a].qd_begin() + k]);
      if (finite) G.limited.push_back(k);
    }
    const int nl = static_cast<int>(G.limited.size());
    G.impulse_base = limit_cell_count_;
    limit_cell_count_ += G.blocks * 2 * nl * W;
    for (int k = 0; k < G.world_count; ++k)
      for (int m = 0; m < nl; ++m) {
        const int slot = limit_slot[art_[G.arts[k]].qd_begin() + G.limited[m]];
        if (slot < 0) continue;
        if (static_cast<int>(limit_cell_.size()) < 2 * slot + 2) limit_cell_.resize(2 * slot + 2, -1);
        for (int side = 0; side < 2; ++side)
          limit_cell_[2 * slot + side] = G.impulse_base + (((k / W) * nl + m) * 2 + side) * W + k % W;
      }
    G.limits.resize(static_cast<size_t>(G.blocks) * 2 * nl);
    for (int b = 0; b < G.blocks; ++b)
      for (int m = 0; m < nl; ++m)
        for (int l = 0; l < W; ++l) {
          const int g = art_[G.arts[b * W + l]].qd_begin() + G.limited[m];
          G.limits[(b * nl + m) * 2][l] = static_cast<T>(model.joint_limit_lower[g]);
          G.limits[(b * nl + m) * 2 + 1][l] = static_cast<T>(model.joint_limit_upper[g]);
        }
    G.soft_limits = dof_softness(G, model, G.limited, model.joint_limit_solref, model.joint_limit_solimp,
                                 G.limit_softness, G.limit_soft);
  }

  // the softness (soft_row.h) of each block's `dofs` of the group, per lane, from a solref and solimp per dof, and
  // the lanes whose row is soft; returns whether some is
  bool dof_softness(const BatchGroup<T>& G, const Model& model, const std::vector<int>& dofs,
                    const std::vector<Scalar>& solref, const std::vector<Scalar>& solimp, std::vector<Softness>& out,
                    std::vector<IntLanes<T>>& soft) const {
    const int n = static_cast<int>(dofs.size());
    out.assign(static_cast<size_t>(G.blocks) * n * W, Softness{});
    soft.assign(static_cast<size_t>(G.blocks) * n, IntLanes<T>{});
    bool any = false;
    for (int b = 0; b < G.blocks; ++b)
      for (int m = 0; m < n; ++m)
        for (int l = 0; l < W; ++l) {
          const int g = art_[G.arts[b * W + l]].qd_begin() + dofs[m];
          const Softness s = softness_of(&solref[2 * g], &solimp[5 * g], model.joint_invweight0[g]);
          out[(static_cast<size_t>(b) * n + m) * W + l] = s;
          soft[static_cast<size_t>(b) * n + m][l] = s.soft() ? -1 : 0;
          any |= s.soft();
        }
    return any;
  }

  // the group's dofs with dry friction and its blocks' frictionloss
  void lay_out_friction(BatchGroup<T>& G, const Model& model) {
    G.frictional.clear();
    for (int k = 0; k < G.topo.dof_count; ++k) {
      bool any = false;
      for (const int a : G.arts) any |= model.joint_frictionloss[art_[a].qd_begin() + k] > 0;
      if (any) G.frictional.push_back(k);
    }
    const int nf = static_cast<int>(G.frictional.size());
    G.frictionloss.resize(static_cast<size_t>(G.blocks) * nf);
    for (int b = 0; b < G.blocks; ++b)
      for (int m = 0; m < nf; ++m)
        for (int l = 0; l < W; ++l)
          G.frictionloss[b * nf + m][l] =
              static_cast<T>(model.joint_frictionloss[art_[G.arts[b * W + l]].qd_begin() + G.frictional[m]]);
    G.soft_friction = dof_softness(G, model, G.frictional, model.joint_friction_solref, model.joint_friction_solimp,
                                   G.friction_softness, G.friction_soft);
  }

  // a scratch per thread, sized for the largest group: every limit row and four contacts a world
  void size_scratch() {
    scratch_.resize(std::max(1, omp_get_max_threads()));
    std::size_t packed = 0;
    int most_dofs = 0;
    for (const BatchGroup<T>& G : groups_) {
      packed = std::max<std::size_t>(packed, G.topo.packed_size());
      most_dofs = std::max(most_dofs, G.topo.dof_count);
    }
    for (ThreadScratch<T>& s : scratch_) {
      s.S.resize(static_cast<size_t>(6) * most_dofs);
      s.H.resize(packed);
      s.factor.resize(packed);
      s.work.resize(groups_.size());
      for (size_t g = 0; g < groups_.size(); ++g) {
        s.work[g].resize(groups_[g].topo);
        s.work[g].bodies.resize(13 * groups_[g].bodies());
        s.rows.resize(
            2 * static_cast<int>(groups_[g].limited.size()) + static_cast<int>(groups_[g].frictional.size()) + 3 * 4,
            groups_[g].topo.dof_count, 4);
      }
    }
  }

  const std::vector<ArticulationView>& art_;
  std::uint64_t step_ = 0;  // steps so far: a factor copied out before this one is stale
  std::vector<BatchGroup<T>> groups_;
  std::vector<std::pair<int, int>> units_;  // (group, block) of the groups that are on
  std::vector<Slot> slot_;                  // per articulation
  std::vector<int> limit_cell_;             // [2 * limit slot + side] (limit_cells)
  int limit_cell_count_ = 0;
  std::vector<ThreadScratch<T>> scratch_;  // per thread
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
