// Pictures of a few worlds without a display or a graphics library: a world's shapes (planes, spheres,
// boxes, capsules) placed at a state's body poses are ray-cast in an orthographic view, lit by one
// light with shadows, into panels of one image written as a PNG.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "engine/model/model.h"

namespace novaphy {

// a shape placed in the world: what a panel draws
struct Solid {
  ShapeType type;
  Transform pose;              // shape frame in the world (a plane: its local XZ plane, normal +Y)
  Vec3 scale;                  // the shape's shape_scale (model.h)
  int color;                   // the body's index among its world's bodies; -1 for a static shape
  std::vector<Scalar> planes;  // a mesh: its hull's face planes [face][4] (outward normal, offset)
};

// world `world`'s shapes, and the shapes every world shares, at the body poses of `state`
std::vector<Solid> world_solids(const Model& model, const State& state, int world);

// an orthographic view from above and to the side of a region, `up` pointing up in the picture
struct Camera {
  Vec3 center;
  Scalar radius = 1;  // the panel shows a disc of this radius around center
  Vec3 up = Vec3::UnitZ();
};

// a camera that frames everything but the planes in any of `frames` (one world's solids at several
// times), looking along the horizontal a little from above, up against `gravity`
Camera frame_solids(const std::vector<std::vector<Solid>>& frames, const Vec3& gravity);

struct Image {
  Image(int width, int height);
  int width, height;
  std::vector<std::uint8_t> rgb;  // rows top to bottom, 3 bytes a pixel
};

// draws `solids` as seen by `camera` into the panel of `image` at (x0, y0) of the given size
void draw_panel(Image& image, int x0, int y0, int width, int height, const std::vector<Solid>& solids,
                const Camera& camera);

// writes `image` as an 8-bit RGB PNG; throws Error when the file cannot be written
void write_png(const Image& image, const std::string& path);

}  // namespace novaphy
