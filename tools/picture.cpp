// Ray casting of shapes in an orthographic view, and a PNG writer (zlib stream by hand: one fixed-Huffman
// deflate block whose matches repeat the previous byte, pixel or row), so the tools need no image library.
#include "tools/picture.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <limits>
#include <utility>

#include "engine/model/error.h"

namespace novaphy {
namespace {

constexpr Scalar kMiss = std::numeric_limits<Scalar>::infinity();
constexpr Scalar kEpsilon = 1e-9;

// a solid's colours by its body's index in its world, and those of the scene around it
constexpr std::array<std::array<int, 3>, 6> kBodyColors{
    {{214, 96, 77}, {67, 147, 195}, {240, 180, 60}, {90, 170, 110}, {150, 110, 190}, {60, 170, 170}}};
constexpr std::array<int, 3> kStaticColor{150, 150, 150}, kFloorLight{205, 205, 200}, kFloorDark{175, 175, 170};
constexpr std::array<int, 3> kSky{232, 238, 244}, kGutter{255, 255, 255};

// the view's frame: forward (from the camera into the scene), right and up in the picture
struct Basis {
  Vec3 forward, right, up;
};

// horizontal directions s1, s2 with s1 x s2 = up
std::pair<Vec3, Vec3> horizontal(const Vec3& up) {
  const Vec3 side = std::abs(up.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  const Vec3 s1 = (side - up * side.dot(up)).normalized();
  return {s1, up.cross(s1)};
}

// a direction `elevation` above the horizontal at `azimuth` about up (radians)
Vec3 direction(const Vec3& up, Scalar azimuth, Scalar elevation) {
  const auto [s1, s2] = horizontal(up);
  return std::cos(elevation) * (std::cos(azimuth) * s1 + std::sin(azimuth) * s2) + std::sin(elevation) * up;
}

// the camera looks at the scene from the front right of +X (a robot's usual forward), 20 degrees up; the
// light comes from further round and higher
constexpr Scalar kAzimuth = -1.05, kElevation = 0.35, kLightAzimuth = -1.7, kLightElevation = 0.95;

Basis basis(const Camera& camera) {
  Basis b;
  b.forward = -direction(camera.up, kAzimuth, kElevation);
  b.right = b.forward.cross(camera.up).normalized();
  b.up = b.right.cross(b.forward);
  return b;
}

// the radius of a sphere about the solid's origin that holds it (planes: none)
Scalar extent(const Solid& s) {
  switch (s.type) {
    case ShapeType::Sphere: return s.scale.x();
    case ShapeType::Box: return s.scale.norm();
    case ShapeType::Capsule: return s.scale.x() + s.scale.y();
    case ShapeType::Cylinder: return std::hypot(s.scale.x(), s.scale.y());
    case ShapeType::Ellipsoid: return s.scale.maxCoeff();
    case ShapeType::Mesh: return s.scale.norm();
    case ShapeType::Plane: return kMiss;
  }
  return kMiss;
}

// the nearest t > 0 where the ray o + t d (d of unit length) enters the sphere of radius r about c
Scalar hit_sphere(const Vec3& o, const Vec3& d, const Vec3& c, Scalar r) {
  const Vec3 oc = o - c;
  const Scalar b = oc.dot(d), disc = b * b - (oc.squaredNorm() - r * r);
  if (disc < 0) return kMiss;
  const Scalar t = -b - std::sqrt(disc);
  return t > kEpsilon ? t : kMiss;
}

// the nearest t > 0 where the ray o + t d enters the side of the cylinder of radius r about local Y within
// |y| <= h (kMiss where it does not), and the outward normal there into n
Scalar hit_side(const Vec3& o, const Vec3& d, Scalar r, Scalar h, Vec3& n) {
  const Scalar a = d.x() * d.x() + d.z() * d.z();
  if (a <= kEpsilon) return kMiss;
  const Scalar b = o.x() * d.x() + o.z() * d.z(), c = o.x() * o.x() + o.z() * o.z() - r * r;
  const Scalar disc = b * b - a * c;
  if (disc < 0) return kMiss;
  const Scalar side = (-b - std::sqrt(disc)) / a;
  const Vec3 p = o + side * d;
  if (side <= kEpsilon || std::abs(p.y()) > h) return kMiss;
  n = Vec3(p.x(), 0, p.z()) / r;
  return side;
}

// the ray's entry into the ellipsoid of semi-axes r (a unit sphere in coordinates scaled by them), its normal into n
Scalar hit_ellipsoid(const Vec3& o, const Vec3& d, const Vec3& r, Vec3& n) {
  const Vec3 os = o.cwiseQuotient(r), ds = d.cwiseQuotient(r);
  const Scalar a = ds.squaredNorm(), b = os.dot(ds), disc = b * b - a * (os.squaredNorm() - 1);
  if (disc < 0) return kMiss;
  const Scalar enter = (-b - std::sqrt(disc)) / a;
  if (enter <= kEpsilon) return kMiss;
  n = (o + enter * d).cwiseQuotient(r.cwiseProduct(r)).normalized();
  return enter;
}

// the ray's entry into a hull's half-spaces (planes [face][4]): the last face plane entered before the first left
Scalar hit_hull(const Vec3& o, const Vec3& d, const std::vector<Scalar>& planes, Vec3& n) {
  Scalar enter = -kMiss, leave = kMiss;
  for (size_t f = 0; f < planes.size(); f += 4) {
    const Vec3 face(planes[f], planes[f + 1], planes[f + 2]);
    const Scalar towards = face.dot(d), gap = planes[f + 3] - face.dot(o);
    if (std::abs(towards) < kEpsilon) {
      if (gap < 0) return kMiss;
    } else if (towards < 0 && gap / towards > enter) {
      enter = gap / towards, n = face;
    } else if (towards > 0) {
      leave = std::min(leave, gap / towards);
    }
  }
  return enter <= leave && enter > kEpsilon ? enter : kMiss;
}

// the ray's entry into solid s: its distance and the outward normal there (world frame)
Scalar hit(const Solid& s, const Vec3& o_world, const Vec3& d_world, Vec3& normal) {
  const Quat to_local = s.pose.q.conjugate();
  const Vec3 o = to_local * (o_world - s.pose.p), d = to_local * d_world;
  Scalar t = kMiss;
  Vec3 n = Vec3::Zero();
  switch (s.type) {
    case ShapeType::Plane:
      if (d.y() < -kEpsilon && (t = -o.y() / d.y()) > kEpsilon) n = Vec3::UnitY();
      break;
    case ShapeType::Sphere:
      t = hit_sphere(o, d, Vec3::Zero(), s.scale.x());
      n = (o + t * d) / s.scale.x();
      break;
    case ShapeType::Box: {
      // slabs: the last plane the ray enters before it first leaves one
      Scalar enter = -kMiss, leave = kMiss;
      for (int i = 0; i < 3; ++i) {
        const Scalar h = s.scale[i];
        if (std::abs(d[i]) < kEpsilon) {
          if (std::abs(o[i]) > h) return kMiss;
          continue;
        }
        Scalar t1 = (-h - o[i]) / d[i], t2 = (h - o[i]) / d[i];
        const Scalar side = d[i] > 0 ? -1 : 1;
        if (t1 > t2) std::swap(t1, t2);
        if (t1 > enter) {
          enter = t1;
          n = side * Vec3::Unit(i);
        }
        leave = std::min(leave, t2);
      }
      if (enter <= leave && enter > kEpsilon) t = enter;
      break;
    }
    case ShapeType::Cylinder: {
      t = hit_side(o, d, s.scale.x(), s.scale.y(), n);
      for (const Scalar end : {-s.scale.y(), s.scale.y()}) {
        if (std::abs(d.y()) < kEpsilon) break;
        const Scalar cap = (end - o.y()) / d.y();
        const Vec3 p = o + cap * d;
        if (cap > kEpsilon && cap < t && p.x() * p.x() + p.z() * p.z() <= s.scale.x() * s.scale.x())
          t = cap, n = Vec3(0, end > 0 ? 1 : -1, 0);
      }
      break;
    }
    case ShapeType::Ellipsoid: t = hit_ellipsoid(o, d, s.scale, n); break;
    case ShapeType::Mesh: t = hit_hull(o, d, s.planes, n); break;
    case ShapeType::Capsule: {
      // the side: the cylinder about local Y within the half height; then the two end spheres
      const Scalar r = s.scale.x(), h = s.scale.y();
      t = hit_side(o, d, r, h, n);
      for (const Scalar end : {-h, h}) {
        const Vec3 c(0, end, 0);
        const Scalar cap = hit_sphere(o, d, c, r);
        if (cap < t) {
          t = cap;
          n = (o + cap * d - c) / r;
        }
      }
      break;
    }
  }
  if (t < kMiss) normal = s.pose.q * n;
  return t;
}

// whether the ray can reach solid s at all: its holding sphere meets the ray's line
bool may_hit(const Solid& s, Scalar radius, const Vec3& o, const Vec3& d) {
  if (s.type == ShapeType::Plane) return true;
  const Vec3 w = s.pose.p - o;
  const Scalar along = w.dot(d);
  return w.squaredNorm() - along * along <= radius * radius;
}

// 1, 2 or 5 times a power of ten near x
Scalar round_size(Scalar x) {
  const Scalar decade = std::pow(10.0, std::floor(std::log10(x)));
  for (const Scalar m : {1.0, 2.0, 5.0})
    if (m * decade >= x) return m * decade;
  return 10 * decade;
}

class Panel {
 public:
  Panel(const std::vector<Solid>& solids, const Camera& camera)
      : solids_(solids),
        camera_(camera),
        basis_(basis(camera)),
        light_(direction(camera.up, kLightAzimuth, kLightElevation)) {
    for (const Solid& s : solids) extent_.push_back(extent(s));
    tile_ = round_size(0.4 * camera.radius);
  }

  // the colour seen along the ray through (x, y) of the view plane (metres right and up of the centre)
  std::array<Scalar, 3> shade(Scalar x, Scalar y) const {
    const Vec3 d = basis_.forward;
    const Vec3 o = camera_.center + x * basis_.right + y * basis_.up - (100 * camera_.radius + 10) * d;
    const Nearest first = nearest(o, d, true);
    if (first.solid < 0) return rgb(kSky, 1);
    const Solid& s = solids_[first.solid];
    const Vec3 p = o + first.t * d, &n = first.normal;
    std::array<int, 3> base = s.color < 0 ? kStaticColor : kBodyColors[s.color % kBodyColors.size()];
    if (s.type == ShapeType::Plane) {
      // a checkered floor out to a few radii from the centre, the sky beyond
      const Vec3 local = s.pose.q.conjugate() * (p - s.pose.p);
      const Vec3 off = p - camera_.center;
      if ((off - camera_.up * off.dot(camera_.up)).norm() > 6 * camera_.radius) return rgb(kSky, 1);
      const long cell = std::lround(std::floor(local.x() / tile_)) + std::lround(std::floor(local.z() / tile_));
      base = cell % 2 ? kFloorDark : kFloorLight;
    }
    const bool lit = n.dot(light_) > 0 && nearest(p + 1e-6 * camera_.radius * n, light_, false).solid < 0;
    return rgb(base, 0.45 + 0.55 * (lit ? n.dot(light_) : 0));
  }

 private:
  struct Nearest {
    int solid = -1;  // -1: none
    Scalar t = kMiss;
    Vec3 normal = Vec3::Zero();
  };

  // the first solid the ray meets (planes only with `planes`)
  Nearest nearest(const Vec3& o, const Vec3& d, bool planes) const {
    Nearest found;
    for (size_t k = 0; k < solids_.size(); ++k) {
      const Solid& s = solids_[k];
      if ((!planes && s.type == ShapeType::Plane) || !may_hit(s, extent_[k], o, d)) continue;
      Vec3 n;
      const Scalar t = hit(s, o, d, n);
      if (t < found.t) found = {static_cast<int>(k), t, n};
    }
    return found;
  }

  static std::array<Scalar, 3> rgb(const std::array<int, 3>& c, Scalar light) {
    return {c[0] * light, c[1] * light, c[2] * light};
  }

  const std::vector<Solid>& solids_;
  Camera camera_;
  Basis basis_;
  Vec3 light_;
  std::vector<Scalar> extent_;
  Scalar tile_;
};

// PNG: CRC-32 of each chunk, Adler-32 of the zlib stream
std::uint32_t crc32(const std::uint8_t* data, size_t n, std::uint32_t crc = 0) {
  static const std::array<std::uint32_t, 256> table = [] {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t k = 0; k < 256; ++k) {
      std::uint32_t c = k;
      for (int b = 0; b < 8; ++b) c = c & 1 ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[k] = c;
    }
    return t;
  }();
  crc = ~crc;
  for (size_t k = 0; k < n; ++k) crc = table[(crc ^ data[k]) & 0xFF] ^ (crc >> 8);
  return ~crc;
}

std::uint32_t adler32(const std::vector<std::uint8_t>& data) {
  std::uint32_t a = 1, b = 0;
  for (const std::uint8_t x : data) {
    a = (a + x) % 65521;
    b = (b + a) % 65521;
  }
  return b << 16 | a;
}

// deflate's bit order: fields least significant bit first, Huffman codes most significant bit first
class BitWriter {
 public:
  void bits(std::uint32_t value, int count) {
    acc_ |= static_cast<std::uint64_t>(value) << fill_;
    fill_ += count;
    while (fill_ >= 8) {
      out.push_back(static_cast<std::uint8_t>(acc_));
      acc_ >>= 8;
      fill_ -= 8;
    }
  }
  void code(std::uint32_t value, int count) {
    std::uint32_t reversed = 0;
    for (int k = 0; k < count; ++k) reversed |= ((value >> k) & 1) << (count - 1 - k);
    bits(reversed, count);
  }
  void flush() {
    if (fill_ > 0) bits(0, 8 - fill_);
  }
  std::vector<std::uint8_t> out;

 private:
  std::uint64_t acc_ = 0;
  int fill_ = 0;
};

// a literal or length symbol in deflate's fixed Huffman code
void fixed_symbol(BitWriter& w, int symbol) {
  if (symbol < 144) return w.code(0x30 + symbol, 8);
  if (symbol < 256) return w.code(0x190 + symbol - 144, 9);
  if (symbol < 280) return w.code(symbol - 256, 7);
  w.code(0xC0 + symbol - 280, 8);
}

// `length` (3..258) bytes copied from `distance` back
void fixed_match(BitWriter& w, int length, int distance) {
  static constexpr int kLengthBase[] = {3,  4,  5,  6,  7,  8,  9,  10, 11,  13,  15,  17,  19,  23, 27,
                                        31, 35, 43, 51, 59, 67, 83, 99, 115, 131, 163, 195, 227, 258};
  static constexpr int kDistanceBase[] = {1,    2,    3,    4,    5,    7,    9,    13,    17,    25,
                                          33,   49,   65,   97,   129,  193,  257,  385,   513,   769,
                                          1025, 1537, 2049, 3073, 4097, 6145, 8193, 12289, 16385, 24577};
  int l = 28;
  while (kLengthBase[l] > length) --l;
  fixed_symbol(w, 257 + l);
  const int length_extra = l < 8 || l == 28 ? 0 : (l - 4) / 4;
  w.bits(length - kLengthBase[l], length_extra);
  int c = 29;
  while (kDistanceBase[c] > distance) --c;
  w.code(c, 5);
  w.bits(distance - kDistanceBase[c], c < 4 ? 0 : (c - 2) / 2);
}

// a zlib stream of `data`: one fixed-Huffman block, each match the longest repeat at distance 1, 3 or `row`
std::vector<std::uint8_t> zlib_compress(const std::vector<std::uint8_t>& data, int row) {
  BitWriter w;
  w.bits(0x78, 8);
  w.bits(0x01, 8);
  w.bits(1, 1);  // the final block
  w.bits(1, 2);  // fixed Huffman codes
  const size_t n = data.size();
  for (size_t i = 0; i < n;) {
    int best = 0, at = 0;
    for (const int distance : {1, 3, row}) {
      if (static_cast<size_t>(distance) > i || distance > 32768) continue;
      int length = 0;
      while (length < 258 && i + length < n && data[i + length] == data[i + length - distance]) ++length;
      if (length > best) {
        best = length;
        at = distance;
      }
    }
    if (best >= 3) {
      fixed_match(w, best, at);
      i += best;
    } else {
      fixed_symbol(w, data[i++]);
    }
  }
  fixed_symbol(w, 256);
  w.flush();
  const std::uint32_t check = adler32(data);
  for (int shift = 24; shift >= 0; shift -= 8) w.out.push_back(static_cast<std::uint8_t>(check >> shift));
  return w.out;
}

void put32(std::vector<std::uint8_t>& out, std::uint32_t x) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<std::uint8_t>(x >> shift));
}

void chunk(std::vector<std::uint8_t>& out, const char* type, const std::vector<std::uint8_t>& data) {
  put32(out, static_cast<std::uint32_t>(data.size()));
  const size_t start = out.size();
  out.insert(out.end(), type, type + 4);
  out.insert(out.end(), data.begin(), data.end());
  put32(out, crc32(out.data() + start, out.size() - start));
}

}  // namespace

std::vector<Solid> world_solids(const Model& model, const State& state, int world) {
  model.check(state);
  std::vector<int> index(model.body_count, -1);  // a body's index among its world's bodies
  for (int b = 0, n = 0; b < model.body_count; ++b)
    if (model.body_world[b] == world) index[b] = n++;
  std::vector<Solid> solids;
  for (int s = 0; s < model.shape_count; ++s) {
    if (model.shape_world[s] != world && model.shape_world[s] != -1) continue;
    const int body = model.shape_body[s];
    Solid solid{static_cast<ShapeType>(model.shape_type[s]),
                Transform::from_array(&model.shape_transform[7 * s]),
                Vec3(model.shape_scale[3 * s], model.shape_scale[3 * s + 1], model.shape_scale[3 * s + 2]),
                body < 0 ? -1 : index[body],
                {}};
    if (const int mesh = model.shape_mesh[s]; mesh >= 0)
      solid.planes.assign(model.mesh_face_plane.begin() + 4 * model.mesh_face_start[mesh],
                          model.mesh_face_plane.begin() + 4 * model.mesh_face_start[mesh + 1]);
    if (body >= 0) solid.pose = Transform::from_array(&state.body_q[7 * body]) * solid.pose;
    solids.push_back(solid);
  }
  return solids;
}

Camera frame_solids(const std::vector<std::vector<Solid>>& frames, const Vec3& gravity) {
  Camera camera;
  if (gravity.norm() > 0) camera.up = -gravity.normalized();
  Vec3 lower = Vec3::Constant(kMiss), upper = -lower;
  for (const std::vector<Solid>& solids : frames)
    for (const Solid& s : solids) {
      if (s.type == ShapeType::Plane) continue;
      lower = lower.cwiseMin(s.pose.p - Vec3::Constant(extent(s)));
      upper = upper.cwiseMax(s.pose.p + Vec3::Constant(extent(s)));
    }
  if (!(lower.array() <= upper.array()).all()) return camera;  // nothing but planes: the origin
  camera.center = (lower + upper) / 2;
  // the box's corners seen from the camera: the panel holds the larger of their half width and height
  const Basis b = basis(camera);
  const Vec3 half = (upper - lower) / 2;
  Scalar across = 0, high = 0;
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3 c(corner & 1 ? half.x() : -half.x(), corner & 2 ? half.y() : -half.y(),
                 corner & 4 ? half.z() : -half.z());
    across = std::max(across, std::abs(c.dot(b.right)));
    high = std::max(high, std::abs(c.dot(b.up)));
  }
  camera.radius = 1.1 * std::max({across, high, Scalar(1e-3)});
  return camera;
}

Image::Image(int width, int height) : width(width), height(height), rgb(3 * width * height) {
  for (size_t k = 0; k < rgb.size(); ++k) rgb[k] = static_cast<std::uint8_t>(kGutter[k % 3]);
}

void draw_panel(Image& image, int x0, int y0, int width, int height, const std::vector<Solid>& solids,
                const Camera& camera) {
  const Panel panel(solids, camera);
  const Scalar metres = camera.radius / (std::min(width, height) / 2.0);  // per pixel
  // 2 x 2 samples a pixel, averaged
#pragma omp parallel for schedule(dynamic)
  for (int row = 0; row < height; ++row) {
    for (int col = 0; col < width; ++col) {
      std::array<Scalar, 3> sum{};
      for (int sample = 0; sample < 4; ++sample) {
        const Scalar x = (col + 0.25 + 0.5 * (sample & 1) - width / 2.0) * metres;
        const Scalar y = (height / 2.0 - row - 0.25 - 0.5 * (sample >> 1)) * metres;
        const std::array<Scalar, 3> c = panel.shade(x, y);
        for (int k = 0; k < 3; ++k) sum[k] += c[k] / 4;
      }
      std::uint8_t* pixel = &image.rgb[3 * (static_cast<size_t>(y0 + row) * image.width + x0 + col)];
      for (int k = 0; k < 3; ++k) pixel[k] = static_cast<std::uint8_t>(std::clamp<Scalar>(std::round(sum[k]), 0, 255));
    }
  }
}

void write_png(const Image& image, const std::string& path) {
  // each row: filter type 1 (each byte less the one a pixel before), then its bytes
  const int stride = 3 * image.width + 1;
  std::vector<std::uint8_t> raw(static_cast<size_t>(stride) * image.height);
  for (int y = 0; y < image.height; ++y) {
    std::uint8_t* out = &raw[static_cast<size_t>(y) * stride];
    const std::uint8_t* in = &image.rgb[3 * static_cast<size_t>(y) * image.width];
    out[0] = 1;
    for (int k = 0; k < 3 * image.width; ++k) out[1 + k] = static_cast<std::uint8_t>(in[k] - (k >= 3 ? in[k - 3] : 0));
  }
  std::vector<std::uint8_t> header;
  put32(header, image.width);
  put32(header, image.height);
  header.insert(header.end(), {8, 2, 0, 0, 0});  // 8 bits a channel, RGB, deflate, filters, no interlace
  std::vector<std::uint8_t> png{0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  chunk(png, "IHDR", header);
  chunk(png, "IDAT", zlib_compress(raw, stride));
  chunk(png, "IEND", {});
  std::ofstream file(path, std::ios::binary);
  file.write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
  if (!file) fail("cannot write the picture ", path);
}

}  // namespace novaphy
