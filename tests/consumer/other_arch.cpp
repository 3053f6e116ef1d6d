// Includes NovaPhy's headers in a compilation for a target whose vectors differ from the library's:
// tests/consumer/run.cmake expects kernels/lanes.h to stop it with a message naming the library's -march.
#include "engine/solver/solver_featherstone.h"

int main() { return novaphy::kVectorBytes > 0 ? 0 : 1; }
