// Values the fuzz targets draw: mostly ordinary numbers, sometimes the edges validation must catch.
#pragma once

#include <fuzzer/FuzzedDataProvider.h>

#include <cmath>
#include <limits>

#include "kernels/spatial.h"

namespace novaphy::fuzz {

inline Scalar number(FuzzedDataProvider& data) {
  switch (data.ConsumeIntegralInRange(0, 9)) {
    case 0: return 0;
    case 1: return -1;
    case 2: return std::numeric_limits<Scalar>::quiet_NaN();
    case 3: return std::numeric_limits<Scalar>::infinity();
    case 4: return 1e-12;
    case 5: return 1e12;
    default: return data.ConsumeFloatingPointInRange<Scalar>(-3, 3);
  }
}

inline Vec3 vec3(FuzzedDataProvider& data) { return Vec3(number(data), number(data), number(data)); }

inline Transform transform(FuzzedDataProvider& data) {
  Transform T;
  if (data.ConsumeBool()) return T;
  T.p = vec3(data);
  T.q = Quat(number(data), number(data), number(data), number(data));
  return T;
}

}  // namespace novaphy::fuzz
