// The installed MPI component: two pendulum worlds in a ShardedBatch on however many ranks run it
// (one, started without mpirun), gathered on the root after half a second of swinging.
#include <mpi.h>

#include <cstdio>
#include <vector>

#include "engine/mpi/sharded_batch.h"

int main(int argc, char** argv) {
  using namespace novaphy;
  MPI_Init(&argc, &argv);
  const WorldBuilder pendulum = [](ModelBuilder& builder, int w) {
    const int link = builder.add_body(RigidBody::from_box(1, Vec3(0.05, 0.5, 0.05)));
    JointOptions options;
    options.dof.axis = Vec3::UnitZ();
    options.parent_xform.p = Vec3(2.0 * w, 0, 0);
    options.child_xform.p = Vec3(-0.5, 0, 0);
    builder.add_joint_revolute(-1, link, options);
  };
  ShardedBatch batch(MPI_COMM_WORLD, 2, ModelBuilder(), pendulum);
  for (int k = 0; k < 60; ++k) batch.step(1.0 / 120);
  std::vector<double> q(batch.rank() == 0 ? 2 : 0);
  batch.gather<double>(batch.state().joint_q, q);
  const bool swung = batch.rank() != 0 || (q[0] < -1.0 && q[0] == q[1]);
  if (batch.rank() == 0) std::printf("consumer_mpi: both worlds swung to %.3f and %.3f rad\n", q[0], q[1]);
  MPI_Finalize();
  return swung ? 0 : 1;
}
