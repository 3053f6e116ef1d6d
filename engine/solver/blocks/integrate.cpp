// The Integrate and Store stages of one block: the coordinates stepped, the divergence guard's test
// (engine/solver/parts/guard.h), and the worlds' new state and body poses and velocities written out.
#include "engine/solver/blocks/block_data.h"
#include "engine/solver/parts/guard.h"
#include "kernels/batch/lane_math.h"
#include "kernels/stream.h"

namespace novaphy {

template <typename T>
IntLanes<T> block_integrate(const BatchGroup<T>& G, int b, const StepContext& step, BatchWork<T>& w, bool carried,
                            bool store) {
  constexpr int W = kLanes<T>;
  const int nq = G.topo.coord_count, nv = G.topo.dof_count;
  if (!carried) {
    gather_lanes<T>(&G.q_off[b * W], step.in->joint_q.data(), nq, w.q.data());
    gather_lanes<T>(&G.qd_off[b * W], step.qd, nv, w.qd.data());
  }
  batch_integrate(G.topo, w.q.data(), w.qd.data(), static_cast<T>(step.dt), w.q_next.data());
  // (x, the right-hand side of the dynamics, is free once they solved it: it takes the guard's weights)
  gather_lanes<T>(&G.qd_off[b * W], step.energy_weight, nv, w.x.data());
  bool diverged[W];
  divergence_test(w.q_next.data(), nq, w.qd.data(), w.x.data(), nv, step.settings.divergence_speed,
                  step.settings.divergence_energy, diverged);
  IntLanes<T> written{};
  for (int l = 0; l < G.lanes_in(b); ++l) {
    const int a = G.arts[b * W + l];
    step.diverged[a] = diverged[l] || step.flagged[a];
    if (store && (step.diverged[a] || step.factor_failure[a] >= 0)) continue;
    written[l] = -1;
  }
  scatter_lanes<T>(&G.q_off[b * W], w.q_next.data(), nq, written, store ? step.out->joint_q.data() : step.q_next);
  scatter_lanes<T>(&G.qd_off[b * W], w.qd.data(), nv, written, store ? step.out->joint_qd.data() : step.qd);
  return written;
}

namespace {

using namespace lane_math;

// the block's rows of body_q and body_qd from lanes x_q [body][7] and x_qd [body][6] into `out`
template <typename T>
void write_bodies(const BatchGroup<T>& G, int b, const Lanes<T>* x_q, const Lanes<T>* x_qd, const IntLanes<T>& written,
                  State& out, bool stream) {
  constexpr int W = kLanes<T>;
  const int nb = G.bodies(), lanes = G.lanes_in(b);
  const int* body = &G.body[static_cast<size_t>(b) * W * nb];
  const int* place = G.body_place.data();
  const IntLanes<T> store = written & real_lanes(G, b);
  bool all = true;
  for (int l = 0; l < lanes; ++l) all &= written[l] != 0;
  if (G.contiguous[b]) {
    // the block's worlds' bodies follow each other: each world's rows of body_q, then of body_qd, are
    // written at once, with `stream` (and every lane written) around the caches
    auto write = [&](const Lanes<T>* x, int width, std::vector<Scalar>& field) {
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

}  // namespace

template <typename T>
void block_store(const BatchGroup<T>& G, int b, BatchWork<T>& w, Lanes<T>* o, const Lanes<T>* q,
                 const IntLanes<T>& written, State& out, bool stream) {
  const BatchTopology<T>& topo = G.topo;
  batch_kinematics(topo, q, w, o);
  batch_subspace_velocity(topo, o, w.qd.data(), w);
  const int n = G.links(), nb = G.bodies();
  // in lanes first, every body's body_q then every body's body_qd, each body at its place (a world's rows
  // of each array in the model's order when its bodies are one run)
  Lanes<T>* x_q = w.bodies.data();
  Lanes<T>* x_qd = x_q + 7 * nb;
  // body k: body_q = [p, Q], body_qd = [velocity of the centre of mass, angular velocity]
  auto put = [&](int k, const Lanes<T>* p, const Lanes<T>* Q, const Lanes<T>* com, const Lanes<T>* v) {
    Lanes<T>* x = x_q + 7 * k;
    Lanes<T>* y = x_qd + 6 * k;
    Lanes<T> c[3];
    body_point<T>(p, Q, com, o, c);
    for (int m = 0; m < 3; ++m) x[m] = p[m];
    for (int m = 0; m < 4; ++m) x[3 + m] = Q[m];
    y[0] = v[3] + v[1] * c[2] - v[2] * c[1];
    y[1] = v[4] + v[2] * c[0] - v[0] * c[2];
    y[2] = v[5] + v[0] * c[1] - v[1] * c[0];
    for (int m = 0; m < 3; ++m) y[3 + m] = v[m];
  };
  const Lanes<T>* body_com = G.body_com(b);
  const int* place = G.body_place.data();
  for (int i = 0; i < n; ++i) put(place[i], &w.p[3 * i], &w.Q[4 * i], body_com + 3 * i, &w.v[6 * i]);
  for (size_t k = 0; k < G.welds.size(); ++k) {
    const auto& weld = G.welds[k];
    Lanes<T> p[3], Q[4];
    weld_pose<T>(weld, w, p, Q);
    put(place[n + k], p, Q, body_com + 3 * (n + k), &w.v[6 * weld.link]);
  }
  write_bodies(G, b, x_q, x_qd, written, out, stream);
}

#define NOVAPHY_INSTANTIATE(T)                                                                                        \
  template IntLanes<T> block_integrate(const BatchGroup<T>&, int, const StepContext&, BatchWork<T>&, bool, bool);     \
  template void block_store(const BatchGroup<T>&, int, BatchWork<T>&, Lanes<T>*, const Lanes<T>*, const IntLanes<T>&, \
                            State&, bool);
NOVAPHY_INSTANTIATE(float)
NOVAPHY_INSTANTIATE(double)
#undef NOVAPHY_INSTANTIATE

}  // namespace novaphy
