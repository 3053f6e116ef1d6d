#include "tools/mujoco_oracle.h"

#include <algorithm>

#include "engine/eval/eval.h"

namespace novaphy {

namespace {

Scalar relative(const MatX& novaphy, const MatX& mujoco) {
  if (mujoco.size() == 0) return 0;
  return (novaphy - mujoco).cwiseAbs().maxCoeff() / std::max<Scalar>(1, mujoco.cwiseAbs().maxCoeff());
}

Scalar uniform(std::mt19937& rng, Scalar lo, Scalar hi) { return std::uniform_real_distribution<Scalar>(lo, hi)(rng); }

void random_unit_quat(std::mt19937& rng, mjtNum* q) {
  std::normal_distribution<Scalar> n;
  for (int k = 0; k < 4; ++k) q[k] = n(rng);
  mju_normalize4(q);
}

}  // namespace

Scalar OracleErrors::max() const {
  return std::max({body_pose, body_velocity, mass_matrix, bias, qdd_crba, qdd_aba, qdd_batched});
}

void OracleErrors::accumulate(const OracleErrors& o) {
  body_pose = std::max(body_pose, o.body_pose);
  body_velocity = std::max(body_velocity, o.body_velocity);
  mass_matrix = std::max(mass_matrix, o.mass_matrix);
  bias = std::max(bias, o.bias);
  qdd_crba = std::max(qdd_crba, o.qdd_crba);
  qdd_aba = std::max(qdd_aba, o.qdd_aba);
  qdd_batched = std::max(qdd_batched, o.qdd_batched);
}

MujocoOracle::MujocoOracle(const std::string& path) {
  m_ = load_mujoco_model(path);
  m_->opt.disableflags |= mjDSBL_CONSTRAINT;
  d_ = mj_makeData(m_);
  ModelBuilder builder;
  import_ = import_mujoco_model(builder, m_);
  model_ = builder.finalize();
}

MujocoOracle::~MujocoOracle() {
  mj_deleteData(d_);
  mj_deleteModel(m_);
}

OracleErrors MujocoOracle::compare_random_state(std::mt19937& rng) {
  const int nv = m_->nv;
  for (int j = 0; j < m_->njnt; ++j) {
    mjtNum* q = d_->qpos + m_->jnt_qposadr[j];
    switch (m_->jnt_type[j]) {
      case mjJNT_HINGE: q[0] = uniform(rng, -M_PI, M_PI); break;
      case mjJNT_SLIDE: q[0] = uniform(rng, -0.5, 0.5); break;
      case mjJNT_BALL: random_unit_quat(rng, q); break;
      case mjJNT_FREE:
        for (int k = 0; k < 3; ++k) q[k] = uniform(rng, -1, 1);
        random_unit_quat(rng, q + 3);
        break;
    }
  }
  for (int k = 0; k < nv; ++k) d_->qvel[k] = uniform(rng, -2, 2);
  mju_zero(d_->qfrc_applied, nv);
  mju_zero(d_->ctrl, m_->nu);
  mju_zero(d_->xfrc_applied, 6 * m_->nbody);
  mj_forward(m_, d_);

  State state = model_.state();
  import_.to_joint_q(d_->qpos, state.joint_q.data());
  import_.to_joint_qd(d_->qpos, d_->qvel, state.joint_qd.data());
  eval_fk(model_, state);
  const MatX T = import_.velocity_map(d_->qpos);

  OracleErrors e;
  // body poses and velocities ([v_com; w] against MuJoCo's [w; v] at the centre of mass)
  MatX pose_np(m_->nbody, 12), pose_mj(m_->nbody, 12), vel_np(m_->nbody, 6), vel_mj(m_->nbody, 6);
  pose_np.setZero(), pose_mj.setZero(), vel_np.setZero(), vel_mj.setZero();
  for (int b = 1; b < m_->nbody; ++b) {
    const int nb = import_.body_map[b];
    if (nb < 0) continue;
    const Transform X = Transform::from_array(&state.body_q[7 * nb]);
    const Mat3 R = X.rotation();
    pose_np.row(b) << X.p.transpose(), Eigen::Map<const Eigen::Matrix<Scalar, 1, 9>>(R.data());
    const Mat3 R_mj = Eigen::Map<const Eigen::Matrix<Scalar, 3, 3, Eigen::RowMajor>>(d_->xmat + 9 * b);
    pose_mj.row(b) << Eigen::Map<const Eigen::Matrix<Scalar, 1, 3>>(d_->xpos + 3 * b),
        Eigen::Map<const Eigen::Matrix<Scalar, 1, 9>>(R_mj.data());
    mjtNum v[6];
    mj_objectVelocity(m_, d_, mjOBJ_BODY, b, v, 0);
    vel_mj.row(b) << v[3], v[4], v[5], v[0], v[1], v[2];
    vel_np.row(b) = Eigen::Map<const Eigen::Matrix<Scalar, 1, 6>>(&state.body_qd[6 * nb]);
  }
  e.body_pose = relative(pose_np, pose_mj);
  e.body_velocity = relative(vel_np, vel_mj);

  // mass matrix and bias forces in MuJoCo's coordinates: H_mj = T^T H T, c_mj = T^T c
  MatX H_mj(nv, nv);
  {
    Eigen::Matrix<mjtNum, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> full(nv, nv);
    mj_fullM(m_, full.data(), d_->qM);
    H_mj = full;
  }
  e.mass_matrix = relative(T.transpose() * eval_mass_matrix(model_, state) * T, H_mj);
  // MuJoCo's passive forces less its tendons' springs and dampers, which NovaPhy counts with the control's
  // forces (engine/model/tendon.h): ten_J^T (-k (L - L_spring) - b V)
  VecX passive = Eigen::Map<const VecX>(d_->qfrc_passive, nv);
  for (int t = 0; t < m_->ntendon; ++t) {
    const mjtNum f = -m_->tendon_stiffness[t] * (d_->ten_length[t] - m_->tendon_lengthspring[t]) -
                     m_->tendon_damping[t] * d_->ten_velocity[t];
    for (int k = 0; k < nv; ++k) passive[k] -= d_->ten_J[t * nv + k] * f;
  }
  const VecX bias_mj = Eigen::Map<const VecX>(d_->qfrc_bias, nv) - passive;
  e.bias = relative(T.transpose() * eval_bias_forces(model_, state), bias_mj);

  // accelerations under random joint forces and body wrenches: tau = T^-T tau_mj = T tau_mj
  for (int k = 0; k < nv; ++k) d_->qfrc_applied[k] = uniform(rng, -5, 5);
  for (int b = 1; b < m_->nbody; ++b) {
    if (import_.body_map[b] < 0) continue;
    for (int k = 0; k < 6; ++k) {
      d_->xfrc_applied[6 * b + k] = uniform(rng, -3, 3);
      state.body_f[6 * import_.body_map[b] + k] = d_->xfrc_applied[6 * b + k];
    }
  }
  Control control = model_.control();
  // motor commands, partly beyond their control range to exercise the clamp
  for (int u = 0; u < m_->nu; ++u) {
    if (import_.actuator_map[u] < 0) continue;
    d_->ctrl[u] = uniform(rng, -1.5, 1.5);
    control.actuator_ctrl[import_.actuator_map[u]] = d_->ctrl[u];
  }
  mj_forward(m_, d_);
  Eigen::Map<VecX>(control.joint_f.data(), nv) = T * Eigen::Map<const VecX>(d_->qfrc_applied, nv);
  const VecX qdd_mj = T * Eigen::Map<const VecX>(d_->qacc, nv);
  e.qdd_crba = relative(eval_forward_dynamics(model_, state, control, ForwardDynamicsMethod::Crba), qdd_mj);
  e.qdd_aba = relative(eval_forward_dynamics(model_, state, control, ForwardDynamicsMethod::Aba), qdd_mj);
  e.qdd_batched = relative(eval_forward_dynamics(model_, state, control, ForwardDynamicsMethod::Batched), qdd_mj);
  return e;
}

}  // namespace novaphy
