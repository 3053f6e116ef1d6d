// CollisionPipeline: broad phase (masked pairs or sweep and prune per world, planes against their world;
// worlds alike a group at a time, a world per lane) and the narrow-phase kernels of kernels/collide,
// writing into a Contacts buffer allocated once. What it builds once for the model stands in three layers, each on
// those before: ShapeFilter (the pairs that may ever collide), WorldShapes (the colliding shapes per world),
// WorldGroups (worlds alike in groups of lanes).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "engine/collision/shape_filter.h"
#include "engine/collision/world_groups.h"
#include "engine/collision/world_shapes.h"
#include "engine/model/model.h"
#include "engine/threads/exclusive_call.h"
#include "engine/threads/parallel.h"
#include "kernels/collide.h"
#include "kernels/convex.h"

namespace novaphy {

// X(type, name, count, width); count is contact_capacity
#define NOVAPHY_CONTACT_FIELDS(X)                 \
  X(int, contact_shape_a, contact_capacity, 1)    \
  X(int, contact_shape_b, contact_capacity, 1)    \
  X(int, contact_body_a, contact_capacity, 1)     \
  X(int, contact_body_b, contact_capacity, 1)     \
  X(Scalar, contact_point, contact_capacity, 3)   \
  X(Scalar, contact_normal, contact_capacity, 3)  \
  X(Scalar, contact_depth, contact_capacity, 1)   \
  X(int, contact_feature, contact_capacity, 1)    \
  X(Scalar, contact_impulse, contact_capacity, 3) \
  X(Scalar, contact_spin_impulse, contact_capacity, 3)

// contacts of one collide(): the first contact_count entries of each array are valid. A collide that finds more
// than contact_capacity grows the arrays (CollisionOptions::on_overflow): the arrays it replaces are kept in
// `retired` while the buffer lives, so a pointer into them (a numpy view fetched before) stays valid but reads
// the old arrays; fetch views again after a collide.
// normal points from shape a to shape b; depth > 0 is penetration; contact_impulse is the
// impulse (world frame, on b) the solver applied, contact_spin_impulse the angular impulse of its torsional and
// rolling rows (world frame, on b; 0 below condim 4), both kept for warm starting the next step
struct Contacts : ModelCounts {
  int contact_capacity = 0;
  int contact_count = 0;
  int contact_dropped = 0;  // contacts the last collide() found beyond the capacity and dropped (on_overflow Drop)
#define NOVAPHY_DECLARE_CONTACT(T, name, count, width) std::vector<T> name;
  NOVAPHY_CONTACT_FIELDS(NOVAPHY_DECLARE_CONTACT)
#undef NOVAPHY_DECLARE_CONTACT
  std::vector<std::shared_ptr<const void>> retired;  // the arrays a growth replaced, kept alive

  // the arrays zeroed at room for `capacity` contacts, the old ones retired
  void grow(int capacity);

  // the previous collide()'s contacts in their order, with the impulses the solver applied to them, and
  // where each of this collide()'s contacts was among them (-1: a new contact)
  std::vector<std::uint64_t> previous_key;
  std::vector<Scalar> previous_impulse;  // [previous][6]: contact_impulse, then contact_spin_impulse
  int previous_count = 0;
  std::vector<int> previous_match;  // [contact]

  static std::uint64_t key(int shape_a, int shape_b, int feature) {
    return (static_cast<std::uint64_t>(shape_a) << 40) | (static_cast<std::uint64_t>(shape_b) << 16) |
           static_cast<std::uint64_t>(feature & 0xffff);
  }
  std::uint64_t key_of(int contact) const {
    return key(contact_shape_a[contact], contact_shape_b[contact], contact_feature[contact]);
  }
  // impulse and spin impulse [6] applied to the same contact (same shapes and feature) at the previous step, or
  // nullptr. collide() matched each contact; a buffer edited since then finds nothing where the keys differ
  const Scalar* previous(int contact) const {
    const int m = contact < static_cast<int>(previous_match.size()) ? previous_match[contact] : -1;
    if (m < 0 || m >= previous_count || previous_key[m] != key_of(contact)) return nullptr;
    return &previous_impulse[6 * static_cast<size_t>(m)];
  }
};

// what collide does when it finds more contacts than the buffer holds
enum class ContactOverflow : int {
  Grow = 0,   // the buffer grows to hold them all (at least doubling)
  Raise = 1,  // collide throws naming the capacity needed; the buffer is left as it was
  Drop = 2,   // those beyond the capacity are dropped, the last worlds' first; contact_dropped counts them
};

struct CollisionOptions {
  int contact_capacity = 0;  // 0: 8 per shape, at least 64
  ContactOverflow on_overflow = ContactOverflow::Grow;
  // contacts are made this far before touching (pairs of soft shapes: within their shape_margin, MuJoCo's rule);
  // the broad phase's bounds reach the larger of this and every shape_margin
  Scalar margin = 0.01;
  bool self_collision = true;      // links of one articulation collide (never a parent with its child)
  int num_threads = 0;             // threads of collide's loops over shapes, worlds and planes; 0: OpenMP's default
  bool count_serial_time = false;  // accumulate collide's wall time and that of its parallel work (serial_seconds)
};

// keeps a reference to the model, which must outlive it
class CollisionPipeline {
 public:
  explicit CollisionPipeline(const Model& model, const CollisionOptions& options = {});

  Contacts contacts() const;
  // contacts between the shapes at the poses of state.body_q; throws Error where another thread's collide on this
  // pipeline is running (one pipeline per thread)
  void collide(const State& state, Contacts& contacts);
  // holds this pipeline's one-call flag for the caller's scope (collides on this thread nest inside it), so work
  // that belongs with a collide (the binding's float32 conversions) is refused with it on another thread
  ExclusiveCall hold() { return ExclusiveCall(busy_, "CollisionPipeline.collide"); }

  const CollisionOptions& options() const { return options_; }
  // wall time of whole collides and of their parallel work (the loops over worlds, shared shapes and planes, the
  // previous contacts kept, when each takes more than one thread), accumulated while options.count_serial_time is
  // on; the rest (the argument checks, the boxes of the shapes of no world, the match with the previous contacts) is
  // the share more threads do not shorten
  const SerialSeconds& serial_seconds() const { return serial_seconds_; }
  void reset_serial_seconds() { serial_seconds_ = {}; }

 private:
  // a contact found by the narrow phase, on its way into the contacts buffer
  struct Found {
    int a, b;
    ContactPoint point;
  };
  // a shape at this collide: its world pose and AABB
  struct Box {
    Transform pose;
    Vec3 lower, upper;
  };
  // shape s's box at the body poses of `state`
  Box box(const State& state, int s) const;
  // shape i of each world in lanes: its pose and bounds
  struct ShapeLanes {
    Lanes<Scalar> pose[7], lower[3], upper[3];
  };
  // a group's sphere against one of its planes in lanes (plane_sphere_contact): the lanes touching, their depths
  // and points
  struct SphereOnPlane {
    Lanes<Scalar> point[3], depth;
    IntLanes<Scalar> touching;
  };
  struct Scratch;
  // the boxes of the worlds of group g into scratch.lanes (a world per lane), and the pairs whose boxes
  // overlap into scratch.hits ([lane][shape]: a bit for each shape after it)
  void group_boxes(const State& state, int g, Scratch& scratch) const;
  // lane l's boxes of the shapes set in `needed` (a bit per shape) from scratch.lanes into scratch.boxes
  void lane_boxes(int l, std::uint64_t needed, Scratch& scratch) const;
  // the planes of group g against its worlds' shapes, in lanes (scratch.lanes): for each of the group's
  // planes, in the order its worlds meet them (WorldGroups::plane_lanes), the shapes that may reach it, into
  // scratch.plane_hits ([lane][plane]: a bit for each shape); the spheres' contacts with them into
  // scratch.plane_spheres ([plane][shape], where a lane may reach it; scratch.spheres: a bit for each sphere)
  void group_planes(int g, Scratch& scratch) const;
  // shape s (a Mesh) as the narrow phase sees its hull: into *view, returned
  const HullView& hull_view(int s, HullView* view) const;
  // shape s at a pose as the convex narrow phase sees it (a Mesh's hull into *hull)
  ConvexShape convex_shape(int s, const Transform& pose, HullView* hull) const;
  // how near shapes a and b are before they touch when their contacts are made: MuJoCo's rule (the larger
  // shape_margin) where both are soft (a solref each), else options.margin
  Scalar pair_margin(int a, int b) const;
  // shapes a < b at those poses, reading the model's entries of shapes read_a and read_b (a and b, or shapes the
  // narrow phase meets alike, WorldGroups::same, in cache)
  void narrow_phase(int a, const Transform& pose_a, int b, const Transform& pose_b, std::vector<Found>& out, int read_a,
                    int read_b) const;
  // the plane p against each of `count` shapes (their boxes) whose AABB reaches it
  void against_plane(int p, const int* shapes, const Box* boxes, int count, std::vector<Found>& out) const;
  // which part of collide's list a contact of this key is in: its world's (the world of its shapes that are not
  // planes), or the last (INT_MAX) where they have none (shapes of no world with each other, planes with them)
  int list_part(std::uint64_t key) const;
  // where each contact in [begin, end) of the buffer was among the previous ones (Contacts::previous_match); none
  // for a contact of a world `reset` marks (State::world_reset where some world is reset, else nullptr)
  void match_previous(Contacts& contacts, int begin, int end, const std::uint8_t* reset) const;
  // the constructor's last stage: the poses and normals of the planes on no body
  void place_static_planes();
  // collide()'s stages:
  // the poses of the planes on bodies and the boxes of the shapes of no world at `state`
  void place_shared(const State& state);
  // whether two boxes overlap (inline: the broad phase's innermost test)
  static bool overlap(const Box& a, const Box& b) {
    return boxes_overlap(a.lower.data(), a.upper.data(), b.lower.data(), b.upper.data());
  }
  // the narrow phase of shapes a and b (either order) where their boxes overlap and they may collide
  // (reading read_a's and read_b's entries, as narrow_phase)
  void test_pair(int a, const Box& A, int b, const Box& B, std::vector<Found>& out, int read_a, int read_b) const {
    if (!overlap(A, B) || !filter_.may_collide(a, b)) return;
    if (a < b)
      narrow_phase(a, A.pose, b, B.pose, out, read_a, read_b);
    else
      narrow_phase(b, B.pose, a, A.pose, out, read_b, read_a);
  }
  // the contacts of group g's worlds into scratch.found: a world alone, or each lane's after group_boxes
  void group_contacts(const State& state, int g, Scratch& scratch);
  // world w's contacts into scratch.found; hits: its boxes are in scratch already, with the pairs found
  // overlapping (per shape, a bit for each shape after it) and the shapes the narrow phase reads (Scratch::read),
  // and its group's planes follow
  void world_contacts(const State& state, int w, Scratch& scratch, const std::uint64_t* hits);
  // world w's pairs by sweep and prune along x (a world of many shapes)
  void sweep_world(int w, const std::vector<Box>& boxes, std::vector<Found>& out);
  // collide on thread t of the region it opened (or alone): the thread's runs of groups of worlds, shared shapes and
  // planes into its scratch; then, unless they overflow the buffer under on_overflow Raise (nothing written), the
  // buffer's contacts and impulses kept as the previous ones, the buffer grown where they overflow it under Grow,
  // the thread's contacts written into it in the order of the loops and of i, whatever the thread count, and the
  // buffer's contacts matched with the previous ones; *found: the contacts found, kept or not (thread 0 writes it)
  void find_on_thread(const State& state, Contacts& contacts, int* found);
  // contact c of the buffer from the narrow phase's
  void write_contact(const Found& found, int c, Contacts& contacts) const;
  // threads collide may take: options.num_threads, or OpenMP's default; one while team_choice() finds a team does
  // not pay
  int thread_count() const;
  // threads for a loop of `count` items, at least `grain` items each
  int team(int count, int grain) const;
  // a loop on `threads` threads counts as parallel work in serial_seconds (on one thread only where collide has
  // no more)
  bool timed(int threads) const;
  static constexpr int kWorldsPerThread = 16;  // worlds (or planes, or shared shapes) a thread at least
  static constexpr int kKeptPerThread = 1024;  // previous contacts a thread at least, where nothing else wakes one
  static constexpr int kMatchStretch = 256;    // contacts matched one after another (match_previous)

  const Model& model_;
  CollisionOptions options_;
  // built once for the model, in this order, and only read after
  ShapeFilter filter_;
  WorldShapes shapes_;
  WorldGroups groups_;
  CallFlag busy_;  // a collide is running (ExclusiveCall)
  Scalar reach_;   // the broad phase's bounds' margin: the larger of options_.margin and every shape_margin
  SerialSeconds serial_seconds_;
  // scratch
  std::vector<Box> shared_boxes_;              // [WorldShapes::shared_others]
  std::vector<Transform> plane_pose_;          // [shape] of the planes
  std::vector<Vec3> plane_normal_;             // [shape] of the planes, their normals (+Y) in the world
  std::vector<std::vector<int>> world_sweep_;  // per world that sweeps: its shapes' local indices, sorted along x
  // per thread: the contacts it found, the boxes of the world it is at, of the group of worlds it is at
  // and their pairs' overlaps; on cache lines of its own (each push writes its vector's end, which would
  // otherwise share a line with another thread's)
  struct alignas(64) Scratch {
    std::vector<Found> found;
    std::size_t loop_end[3] = {};  // where its contacts of each loop of find_on_thread end in found
    std::vector<Box> boxes;
    std::vector<ShapeLanes> lanes;
    std::vector<ShapeLanes> slots;      // a group's slots' boxes (lower, upper)
    std::vector<Lanes<Scalar>> body_q;  // a group's runs of body_q, a number per entry (WorldGroups::run)
    std::vector<std::uint64_t> hits, plane_hits;
    std::vector<SphereOnPlane> plane_spheres;
    std::uint64_t spheres = 0;
    // the group being found: a bit per shape alike in all its worlds, read from its read world's shapes
    // (WorldGroups::read_world)
    std::uint64_t read_same = 0;
    const int* read_shapes = nullptr;
    // the shape whose entries the narrow phase reads for shape i of a world of that group (its `shapes`)
    int read(int i, const std::vector<int>& shapes) const { return read_same >> i & 1 ? read_shapes[i] : shapes[i]; }
  };
  std::vector<Scratch> scratch_;
};

}  // namespace novaphy
