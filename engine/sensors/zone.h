// A touch sensor's zone (MuJoCo's site volume): whether a contact's ray meets it.
#pragma once

#include "engine/model/model.h"

namespace novaphy {

// whether the ray origin + t direction, t >= 0, meets (or starts in) the zone of this type and size centred on the
// origin of its frame, both given in that frame: a Sphere (radius size[0]), Box (half extents), Ellipsoid
// (semi-axes), Capsule or Cylinder (radius size[0], half length size[1] along z)
bool ray_meets_zone(ShapeType type, const Vec3& size, const Vec3& origin, const Vec3& direction);

}  // namespace novaphy
