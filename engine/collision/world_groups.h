// WorldGroups: consecutive worlds alike (the same shapes in the same order, the same pairs, the same planes) in
// groups of up to kLanes, a world per lane, whose boxes, pairs' overlaps and planes' reach each collide finds
// together (CollisionPipeline's group_boxes and group_planes); per group, what its lanes read: its shapes' bodies
// and the runs they lie in, the shapes the same in all its worlds, its slots, its planes. Built once for a model on
// its ShapeFilter and WorldShapes; read-only after.
#pragma once

#include <cstdint>
#include <vector>

#include "engine/collision/shape_filter.h"
#include "engine/collision/world_shapes.h"
#include "engine/model/model.h"
#include "kernels/lanes.h"

namespace novaphy {

class WorldGroups {
 public:
  WorldGroups(const Model& model, const ShapeFilter& filter, const WorldShapes& shapes);

  int count() const { return static_cast<int>(first.size()) - 1; }

  std::vector<int> first;  // the first world of each group, then world_count
  // per group of several worlds: where its bodies start in body (-1: a world alone); per shape of its worlds and
  // lane, the shape's body or -1 (lanes past the group's: the first world's again); a bit per shape the same in
  // all its worlds (its local pose and size, and what the narrow phase reads of it)
  std::vector<int> body_start;
  std::vector<int> body;
  std::vector<std::uint64_t> same;
  // per group of several worlds: the world whose shapes it reads for those the same in all its worlds, the last
  // group's where they are alike (a replicated robot's groups all read one world's, which stays in cache), else
  // its first
  std::vector<int> read_world;
  // per group of several worlds whose shapes' bodies lie in a run of bodies each, at the same places in
  // every run (a replicated robot's): its runs' length (0: no such runs) and each lane's first body; per
  // shape of the group (from body_start / kLanes), its body's place in the run, or -1
  struct BodyRun {
    int length = 0;
    int first[kLanes<Scalar>] = {};
  };
  std::vector<BodyRun> run;
  std::vector<int> run_place;
  // per group of several worlds, its slots: the shapes on one body in every lane (or a shape on none) share a
  // slot, whose box joins theirs. [group] where its slots start, then the end; per slot, a bit per shape in it and
  // a bit per slot whose shapes some shape of it may collide with (after it, as WorldShapes::world_pairs):
  // group_boxes tests two slots' shapes only where the slots' boxes overlap
  std::vector<int> slot_start;
  std::vector<std::uint64_t> slot_shapes, slot_pairs;
  // [group] where its planes start (in plane_shapes, _read and _still, and a lane each in plane_lanes), then the
  // end; per plane of a group (in plane_order): a bit per shape may_collide lets meet it
  std::vector<int> plane_start;
  std::vector<std::uint64_t> plane_shapes;
  // per plane of a group: each lane's plane ([plane][lane]; lanes past the group's, the first world's); the plane
  // whose entries the narrow phase reads for every lane where they are alike in all (one read by a group before
  // where alike, else the first world's; -1: each its own); 1 where the lanes' planes are fixed (on no body) at
  // that plane's place, whose pose group_planes then reads for all
  std::vector<int> plane_lanes, plane_read;
  std::vector<std::uint8_t> plane_still;

 private:
  // the constructor's stages, in this order:
  // consecutive worlds alike into groups (first)
  void group_worlds(const Model& model, const ShapeFilter& filter, const WorldShapes& shapes);
  // per group of several worlds: its shapes' bodies and sameness, its runs of bodies, its planes' reach, its slots
  void describe_groups(const Model& model, const ShapeFilter& filter, const WorldShapes& shapes);
  // whether worlds v and w can be found together
  static bool alike(const Model& model, const ShapeFilter& filter, const WorldShapes& shapes, int v, int w);
  // group g's shapes' bodies in each lane (body), which shapes are the same in all its worlds and the world it reads
  // them from (read_world: last_read, the group before's, where they are alike to its own)
  void group_shapes(const Model& model, const WorldShapes& shapes, int g, int last_read);
  // group g's runs of bodies (run, run_place), where its worlds have them
  void group_runs(const WorldShapes& shapes, int g);
  // group g's planes in the order its worlds meet them, each with the shapes that may reach it, its lanes' planes
  // and the plane read for them (read_planes: those read by the groups before, a few)
  void group_plane_reach(const Model& model, const ShapeFilter& filter, const WorldShapes& shapes, int g,
                         std::vector<int>& read_planes);
  // group g's slots (slot_shapes, slot_pairs)
  void group_slots(const WorldShapes& shapes, int g);
};

}  // namespace novaphy
