#include "kernels/batch/integrate.h"

#include "kernels/batch/lane_math.h"

namespace novaphy {

using namespace lane_math;

template <typename T>
void batch_integrate(const BatchTopology<T>& topo, const V<T>* q, const V<T>* qd, T dt, V<T>* q_out) {
  for (const auto& k : topo.link) {
    const V<T>* x = q + k.q_start;
    const V<T>* v = qd + k.qd_start;
    V<T>* y = q_out + k.q_start;
    switch (k.type) {
      case JointType::Revolute:
      case JointType::Prismatic: y[0] = x[0] + dt * v[0]; break;
      case JointType::Ball: {
        // the child frame turns by dt w (w in the child frame): q exp(dt w)
        const V<T> r[3] = {dt * v[0], dt * v[1], dt * v[2]};
        V<T> Q[4] = {x[0], x[1], x[2], x[3]}, E[4];
        quat_normalize<T>(Q);
        quat_exp<T>(r, E);
        quat_mul(Q, E, y);
        quat_normalize<T>(y);
        break;
      }
      case JointType::Free: {
        // w in the parent frame: exp(dt w) q
        for (int m = 0; m < 3; ++m) y[m] = x[m] + dt * v[3 + m];
        const V<T> r[3] = {dt * v[0], dt * v[1], dt * v[2]};
        V<T> Q[4] = {x[3], x[4], x[5], x[6]}, E[4];
        quat_normalize<T>(Q);
        quat_exp<T>(r, E);
        quat_mul(E, Q, y + 3);
        quat_normalize<T>(y + 3);
        break;
      }
      case JointType::Fixed:
      case JointType::Distance:  // (maximal-coordinate joints: SolverFeatherstone refuses them)
      case JointType::D6:
      case JointType::Cable: break;
    }
  }
}

#define NOVAPHY_INSTANTIATE(T) \
  template void batch_integrate(const BatchTopology<T>&, const Lanes<T>*, const Lanes<T>*, T, Lanes<T>*);
NOVAPHY_INSTANTIATE(float)
NOVAPHY_INSTANTIATE(double)
#undef NOVAPHY_INSTANTIATE

}  // namespace novaphy
