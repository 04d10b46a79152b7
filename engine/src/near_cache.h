// The step's coherent near-set cache: what detect learnt about each triangle around a tool piece
// at earlier ticks, so that a tick only measures the triangles whose verdict its motion since then
// could have changed.
//
// For each piece with bounding capsules, the cache holds a superset: every triangle of the rigid
// objects within `radius_m` of the piece at the pose it was gathered at. A triangle outside it is
// at least radius_m - (how far the piece has moved since) from the piece, so while that stays above
// the tick's reach the superset holds everything in reach. Each entry keeps bounds [lo, hi] on
// its triangle's distance from the piece at a recent pose (one of kNearCacheSlots kept by stamp);
// no point of the piece moves further than its motion bound since, so at the current pose the
// distance lies in [lo - motion, hi + motion]. Where that interval settles the triangle's
// verdict, no test is run; elsewhere the triangle is measured as without the cache.
//
// The cache belongs to the thread's step workspace and is keyed by the model's serial; it
// changes how much the step measures, never what it keeps.
#pragma once

#include "sulcus/engine/bvh.h"
#include "sulcus/engine/renderer.h"
#include "geometry.h"
#include "so3.h"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <algorithm>
#include <limits>

namespace sulcus {

inline constexpr int kNearCacheSlots = 64;       // recent tool poses entries may refer to
inline constexpr int kNearCacheEntries = 4096;   // superset triangles per piece at most
inline constexpr int kNearCacheHash = 8192;      // carry-over table (a power of two, >= 2 entries)
inline constexpr int kSeparationMemo = 4096;     // remembered separations (a power of two)

struct NearCacheEntry {
    uint32_t tri = 0;
    uint16_t object = 0;
    uint64_t stamp = 0;  // the pose the bounds hold at
    double path_m = 0.0;  // the piece's path (NearCache::path_m) at that pose
    double lo = 0.0;     // bounds on the triangle's distance from the piece there (m)
    double hi = 1e300;
    Vec3 direction{0.0};  // GJK's last direction there (world; zero if none): the next search's start
    GjkSimplex simplex{};  // and the simplex it ended on
    // A lower bound there on the gap along `direction` (DistanceBounds::direction_gap), -1e300 for
    // none. The tool's motion since changes it by no more than the origin's displacement along
    // the direction and the turn times the piece's radius (direction_lower_bound): while the tool
    // slides along a surface, far less than its whole motion.
    double direction_gap = -1e300;
};

// A lower bound on the separation of a piece and a triangle of a compliant object at the pose of
// `stamp`, as the guard found it there (solve_candidate): no point moving by d changes the
// separation by more than d, so less the piece's motion since, it bounds the separation at a later
// pose too. The tool rests inside the gingiva for hundreds of ticks at a time, over the same
// triangles: most of them stay clear of the guard's floor by far more than a tick's motion.
struct SeparationMemo {
    uint64_t stamp = 0;  // 0: none
    uint32_t tri = 0;
    uint16_t object = 0;
    uint8_t piece = 0;
    double separation_m = 0.0;
};

struct PieceNearCache {
    bool valid = false;
    Pose pose;              // where the superset was gathered
    double radius_m = 0.0;  // every triangle within this of the piece there is in it
    // At its last use: how much further than the tick's need it reached, and the margin a new
    // superset gets (m).
    double room_m = 0.0, margin_m = 0.0;
    int count = 0;          // entries, grouped by object in object order
    // kNearCacheEntries of them (NearCache's pool: an install swaps them with the build's).
    NearCacheEntry* entries = nullptr;
    // Per entry, its object (entries[i].object): the walk over the entries finds each object's run
    // here without touching an entry's line of memory for every one it skips.
    uint16_t object[kNearCacheEntries];
    // Per entry, when it needs a look again: the lower bound on its triangle's distance from the
    // piece when it was last looked at, plus the piece's path then. `due` less the path now bounds
    // the distance now from below; while that exceeds the reach (and the tolerance), the triangle
    // stays out of reach and the entry is skipped. kNearCacheEntries of them, as `entries`.
    double* due = nullptr;
};

// A piece's next superset, gathered a slice per tick while the current one still holds, so that
// no tick pays for a whole walk: at `pose` (stamp `stamp`), every triangle of the rigid objects
// within radius_m of the piece's capsules, object by object.
struct SupersetBuild {
    bool active = false;
    size_t piece = 0;
    Pose pose;
    uint64_t stamp = 0;
    double path_m = 0.0;  // the piece's path there
    double radius_m = 0.0;
    Vec3 axis[kToolCapsules + 1];  // the piece's capsule chain at `pose`
    size_t object = 0;             // the object being walked; the objects' count once complete
    bool walking = false;          // its walk has started
    CapsuleChainWalk walk;
    int count = 0;
    // kNearCacheEntries each, from NearCache's pool; on install they become the piece's, and
    // the piece's old ones the next build's.
    NearCacheEntry* entries = nullptr;
    double* due = nullptr;  // install's PieceNearCache::due for them
};

struct NearCache {
    uint64_t model_serial = 0;
    // The session tick the cache was left at (State::session, State::ticks and its poses then):
    // any other state starts it afresh.
    uint64_t session = 0;
    uint64_t ticks = 0;
    Pose graphic, last_haptic;
    uint64_t stamp = 0;  // the current pose's stamp (0 before the first)
    Pose ring[kNearCacheSlots];
    uint64_t ring_stamp[kNearCacheSlots] = {};
    // Per slot and piece, how far no point of the piece moved from the slot's pose to the
    // current one (m), worked out once per current pose.
    double motion_m[kNearCacheSlots][kMaxToolPieces] = {};
    uint64_t motion_for[kNearCacheSlots][kMaxToolPieces] = {};
    // Each piece's path: the sum of its motion bounds from pose to pose, stamp by stamp. No point
    // of the piece moved further between two poses than the path between them (the motion bound
    // between two poses is no more than the sum over the poses between), so an entry older than
    // the ring still has a bound, and entries far out of reach need no look until the path has
    // grown by their distance.
    double path_m[kMaxToolPieces] = {};
    // Per slot, how far the tool's origin moved and how far the tool turned from the slot's pose
    // to the current one, worked out once per current pose (origin_motion).
    Vec3 origin_shift[kNearCacheSlots] = {};  // m
    double origin_move[kNearCacheSlots] = {};  // its length (m)
    double origin_turn[kNearCacheSlots] = {};
    uint64_t origin_for[kNearCacheSlots] = {};
    // Per slot, the tool's turn from the slot's pose to the current one (rad), which the motion
    // bounds of every piece and the origin's motion share, worked out once per current pose.
    double turn_rad[kNearCacheSlots] = {};
    uint64_t turn_for[kNearCacheSlots] = {};
    PieceNearCache piece[kMaxToolPieces];
    int32_t table[kNearCacheHash];  // (object, triangle) -> index in the superset being replaced
    // By (object, triangle, piece), one per slot: a later triangle takes a taken slot over.
    SeparationMemo separations[kSeparationMemo];
    SupersetBuild build;            // at most one in progress
    // The entries and dues of the pieces and the build: an install trades the build's for the
    // piece's instead of copying them.
    NearCacheEntry entry_pool[kMaxToolPieces + 1][kNearCacheEntries];
    double due_pool[kMaxToolPieces + 1][kNearCacheEntries];

    NearCache() {
        for (int k = 0; k < kMaxToolPieces; ++k) {
            piece[k].entries = entry_pool[k];
            piece[k].due = due_pool[k];
        }
        build.entries = entry_pool[kMaxToolPieces];
        build.due = due_pool[kMaxToolPieces];
    }
    NearCache(const NearCache&) = delete;
    NearCache& operator=(const NearCache&) = delete;
};

// How far no point of `piece` moves between poses `from` and `to`: its centre's displacement plus
// the turn times its spread, with room for the rounding of placing the tool at either.
// The turn between the poses (rad) as motion_bound takes it.
inline double pose_turn(const Pose& from, const Pose& to) {
    return glm::length(quat_log(to.orientation * glm::conjugate(from.orientation)));
}
// motion_bound with the turn from `from` to `to` (pose_turn) given.
inline double motion_bound_turned(const ToolPiece& piece, const Pose& from, const Pose& to, double turn) {
    const Vec3 a = from.position + from.orientation * piece.centre, b = to.position + to.orientation * piece.centre;
    return glm::length(b - a) + turn * piece.spread_m + 1e-12 + 1e-13 * (glm::length(b) + piece.spread_m);
}
inline double motion_bound(const ToolPiece& piece, const Pose& from, const Pose& to) {
    return motion_bound_turned(piece, from, to, pose_turn(from, to));
}

// How far the tool's origin moves, and how far it turns, from pose `from` to any pose of the
// step's box [lower, upper] about pose `at` (coordinates in `frame`: a pose x of the box is
// at.position + frame x[0..2], Exp(frame x[3..5]) at.orientation), with room for the rounding:
// so no point within r of the origin at `from` moves further than move_m + turn * r. Each such
// pose is a motion from `from` too: by the box shifted by the way from there, since a turn
// composed with a turn differs from their sum by less than the product of their angles, for
// turns this small. Both +infinity for turns over 0.1 rad.
struct BoxMotion {
    double move_m;
    double turn;  // rad
};
inline BoxMotion box_motion(const Pose& from, const Pose& at, const Mat3& frame, const double lower[6],
                            const double upper[6]) {
    const Vec3 d = glm::transpose(frame) * (at.position - from.position);
    const Vec3 r = glm::transpose(frame) * quat_log(at.orientation * glm::conjugate(from.orientation));
    double move2 = 0.0, shifted_turn2 = 0.0, turn2 = 0.0;
    for (int j = 0; j < 3; ++j) {
        const double m = std::max(std::abs(lower[j] + d[j]), std::abs(upper[j] + d[j]));
        const double t = std::max(std::abs(lower[3 + j] + r[j]), std::abs(upper[3 + j] + r[j]));
        const double u = std::max(std::abs(lower[3 + j]), std::abs(upper[3 + j]));
        move2 += m * m;
        shifted_turn2 += t * t;
        turn2 += u * u;
    }
    const double turn = std::sqrt(turn2), turned = glm::length(r);
    constexpr double inf = std::numeric_limits<double>::infinity();
    if (!(turn <= 0.1) || !(turned <= 0.1)) return {inf, inf};
    const double angle = std::sqrt(shifted_turn2) + turned * turn;
    return {std::sqrt(move2) * (1.0 + 1e-9) + 1e-12, angle * (1.0 + 1e-9)};
}

// How far a piece reaches within a box of the step's coordinates, as a whole and for one triangle.
// A pose of the box moves a point p of the piece by at most move + turn |p - o| (o the tool's
// origin, which the box turns about). So a point that comes within the contact distance of
// triangle T at some pose of the box was within D of T at the base, where D is at most the
// piece's reach (|p - o| at most the piece's radius: box_reach) and at most contact + move +
// turn (|p - o| + move) with |p - o| <= D + rho, rho the furthest of T's vertices from o. T is out
// of reach when further than `of(rho)` from the piece at the base. Near the origin -- a probe's
// tip, where it touches -- the turn hardly counts; for the piece as a whole it moves the far end
// of a 12 mm tip by the turn's full arc.
struct PieceReach {
    double reach = 0.0;   // the piece's reach (m), = box_reach
    double move = 0.0;    // the box's largest translation (m)
    double turn = 0.0;    // its largest turn (rad)
    double radius = 0.0;  // the piece's radius (ToolPiece::radius_m)
    double contact = 0.0; // the contact distance (m)
    double room = 0.0;    // the tolerance's room (m)
    Vec3 origin{0.0};     // the tool's origin at the base (world)

    // The furthest of a triangle's vertices from the origin (m).
    double rho(const Vec3& a, const Vec3& b, const Vec3& c) const {
        return std::sqrt(std::max({glm::dot(a - origin, a - origin), glm::dot(b - origin, b - origin),
                                   glm::dot(c - origin, c - origin)}));
    }
    // The reach of a triangle that far.
    double of(double rho) const {
        return std::min(reach, move + turn * (std::min(radius, reach + rho) + move) + contact + room);
    }
};

// A piece's reach within the box [lower, upper] from the base with the tool's origin at `origin`.
inline PieceReach piece_reach(const RendererSettings& S, double piece_radius, const Vec3& origin, const double lower[6],
                              const double upper[6]) {
    double move2 = 0.0, turn2 = 0.0;
    for (int j = 0; j < 6; ++j) {
        const double m = std::max(std::abs(lower[j]), std::abs(upper[j]));
        (j < 3 ? move2 : turn2) += m * m;
    }
    PieceReach r;
    r.move = std::sqrt(move2);
    r.turn = std::sqrt(turn2);
    r.radius = piece_radius;
    r.contact = S.contact_distance_m;
    r.room = 20.0 * S.constraint_tol_m;
    r.origin = origin;
    r.reach = r.move + r.turn * (piece_radius + r.move) + r.contact + r.room;
    return r;
}

// What a distance known to lie in [lo - motion_lo, hi + motion_hi] settles about a triangle at reach
// `reach`: out (GJK to `tol` could not keep it), in (nor drop it), or open (measure it).
enum class Settled { Open, In, Out };
inline Settled settle(double lo, double hi, double motion_lo, double motion_hi, double reach, double tol) {
    if (lo - motion_lo > reach + tol) return Settled::Out;
    if (hi + motion_hi <= reach) return Settled::In;
    return Settled::Open;
}

inline bool same_pose(const Pose& a, const Pose& b) {
    return a.position == b.position && a.orientation == b.orientation;
}

// Forgets every superset and every entry's pose.
inline void near_cache_reset(NearCache& c) {
    for (PieceNearCache& p : c.piece) p.valid = false;
    c.build.active = false;
    c.stamp += kNearCacheSlots;
}

// Makes `pose` the current one (a new stamp unless it is the last one), the pieces' paths grown
// by their motion from the last one; forgets everything when the model is not the one the cache
// was filled for.
inline void near_cache_begin(NearCache& c, const Model& model, const Pose& pose) {
    if (c.model_serial != model.serial) {
        c.model_serial = model.serial;
        near_cache_reset(c);
    }
    const int last = int(c.stamp % kNearCacheSlots);
    const bool follows = c.stamp > 0 && c.ring_stamp[last] == c.stamp;
    if (follows && c.ring[last].position == pose.position && c.ring[last].orientation == pose.orientation) return;
    if (follows)
        for (size_t k = 0; k < model.tool.pieces.size() && k < size_t(kMaxToolPieces); ++k)
            c.path_m[k] += motion_bound(model.tool.pieces[k], c.ring[last], pose);
    ++c.stamp;
    const int slot = int(c.stamp % kNearCacheSlots);
    c.ring[slot] = pose;
    c.ring_stamp[slot] = c.stamp;
}

// The ring's slot of the pose of `stamp`; -1 when that pose is no longer kept.
inline int near_cache_slot(const NearCache& c, uint64_t stamp) {
    if (stamp == 0 || stamp > c.stamp || c.stamp - stamp >= uint64_t(kNearCacheSlots)) return -1;
    const int slot = int(stamp % kNearCacheSlots);
    return c.ring_stamp[slot] == stamp ? slot : -1;
}

// The tool's turn from the pose of a kept slot to the current one (NearCache::turn_rad).
inline double near_cache_turn(NearCache& c, int slot) {
    if (c.turn_for[slot] != c.stamp) {
        c.turn_rad[slot] = pose_turn(c.ring[slot], c.ring[c.stamp % kNearCacheSlots]);
        c.turn_for[slot] = c.stamp;
    }
    return c.turn_rad[slot];
}

// Works out NearCache::motion_m for a kept slot and piece k at the current pose (out of line, so
// that the look-up below stays small enough to inline where it is asked per triangle).
void near_cache_measure_motion(NearCache& c, const Model& model, int slot, size_t k);
// Works out NearCache::origin_shift, origin_move and origin_turn for a kept slot.
void near_cache_measure_origin(NearCache& c, int slot);

// How far no point of piece k (of `model`) moved from the pose of `stamp` to the current one;
// false when that pose is no longer kept.
inline bool near_cache_motion(NearCache& c, const Model& model, uint64_t stamp, size_t k, double& motion) {
    const int slot = near_cache_slot(c, stamp);
    if (slot < 0) return false;
    if (c.motion_for[slot][k] != c.stamp) near_cache_measure_motion(c, model, slot, k);
    motion = c.motion_m[slot][k];
    return true;
}

// How far no point of piece k moved since an entry's pose: as near_cache_motion while that pose is
// kept, else by the path since (with room for its rounding); false for an entry of no pose.
inline bool near_cache_entry_motion(NearCache& c, const Model& model, const NearCacheEntry& e, size_t k,
                                    double& motion) {
    if (near_cache_motion(c, model, e.stamp, k, motion)) return true;
    if (e.stamp == 0 || e.stamp > c.stamp) return false;
    motion = (c.path_m[k] - e.path_m) * (1.0 + 1e-12) + 1e-15 * (1.0 + c.path_m[k]);
    return true;
}

// How far the tool's origin moved between two poses, and by what angle the tool turned: a point
// at distance r from the origin at the first moved at most move_m + turn r (OriginMotion::bound).
struct OriginMotion {
    Vec3 shift{0.0};    // the origin's displacement (m)
    double move_m = 0.0;  // its length
    double turn = 0.0;  // rad
    // With room for the rounding of placing the tool at either pose, as motion_bound's.
    double bound(double r) const {
        return (move_m + turn * r) * (1.0 + 1e-9) + 1e-12 + 1e-13 * (move_m + r);
    }
};

inline OriginMotion origin_motion(const Pose& from, const Pose& to) {
    const Vec3 shift = to.position - from.position;
    return {shift, glm::length(shift), pose_turn(from, to)};
}

// The tool's motion from the pose of `stamp` to the current one; false when that pose is no longer
// kept.
inline bool near_cache_origin_motion(NearCache& c, uint64_t stamp, OriginMotion& motion) {
    const int slot = near_cache_slot(c, stamp);
    if (slot < 0) return false;
    if (c.origin_for[slot] != c.stamp) near_cache_measure_origin(c, slot);
    motion = {c.origin_shift[slot], c.origin_move[slot], c.origin_turn[slot]};
    return true;
}

// How much a triangle's distance from a piece can have changed since it was lo (or hi) at an
// earlier pose, when the tool moved by `om` since and rho bounds the triangle's vertices' distance
// from the tool's origin now. The closest point p of the piece there, at |p - t| >= lo from the
// triangle's point t, lay within |p - t| + |t - o| of the origin o there, and |t - o| is at most
// rho plus the origin's move: p moved by at most move + turn (|p - t| + rho + move), so the
// distance fell by at most that with |p - t| = max(lo, 0) (the factor 1 - turn on |p - t| only
// helps). Likewise it rose by at most that with hi. The piece's own bound (motion_bound, the
// turn times its spread from its centre) is larger wherever the triangle lies near the origin:
// a probe's tip, where it touches.
inline double triangle_motion(const OriginMotion& om, double distance, double rho) {
    return om.bound(std::max(distance, 0.0) + rho + om.move_m);
}

// A lower bound now on the distance between a piece and a triangle whose gap along the unit
// vector n of `direction` (any length, from the triangle towards the piece) was `gap` at an
// earlier pose, the tool having
// moved by `om` since: each point p of the piece moved by the origin's shift plus the turn of
// p - o (o the origin then), which is at most the turn times `piece_radius`, so the piece's least
// extent along n rose by at least n . shift less that and the triangle's most did not move. The
// gap along n bounds the distance below. With room for the rounding of placing the tool at
// either pose (OriginMotion::bound's, less the move it counts). -1e300 for a zero direction.
inline double direction_lower_bound(const OriginMotion& om, const Vec3& direction, double gap, double piece_radius) {
    const double len = glm::length(direction);
    if (!(len > 0.0) || !(gap > -1e299)) return -1e300;
    return gap + glm::dot(direction, om.shift) / len - (om.bound(piece_radius) - om.move_m);
}

inline uint32_t near_cache_hash(uint16_t object, uint32_t tri) {
    uint64_t k = (uint64_t(object) << 32) | tri;
    k *= 0x9E3779B97F4A7C15ull;
    return uint32_t(k >> 40) & (kNearCacheHash - 1);
}

inline SeparationMemo& near_cache_separation_slot(NearCache& c, uint16_t object, uint32_t tri, uint8_t piece) {
    return c.separations[(near_cache_hash(object, tri) + 977u * piece) & (kSeparationMemo - 1)];
}

// Whether the cache's current pose is `pose` (of the model it was filled for): then what it
// remembers of separations holds, less the motion since, there.
inline bool near_cache_at(const NearCache& c, const Model& model, const Pose& pose) {
    const int slot = int(c.stamp % kNearCacheSlots);
    return c.model_serial == model.serial && c.stamp > 0 && c.ring_stamp[slot] == c.stamp &&
           same_pose(c.ring[slot], pose);
}

// A lower bound on the separation of piece k and (object, tri) at the current pose from what the
// memo holds for them (SeparationMemo); -1e300 when it holds nothing of them, or nothing the ring
// still has the pose of.
inline double near_cache_separation(NearCache& c, const Model& model, uint16_t object, uint32_t tri, uint8_t k) {
    const SeparationMemo& s = near_cache_separation_slot(c, object, tri, k);
    double motion = 0.0;
    if (s.tri != tri || s.object != object || s.piece != k || !near_cache_motion(c, model, s.stamp, k, motion))
        return -1e300;
    return s.separation_m - motion;
}

// Remembers a lower bound on the separation of piece k and (object, tri) at the current pose.
inline void near_cache_keep_separation(NearCache& c, uint16_t object, uint32_t tri, uint8_t k, double separation) {
    if (!(separation > -1e300)) return;
    SeparationMemo& s = near_cache_separation_slot(c, object, tri, k);
    s.stamp = c.stamp;
    s.tri = tri;
    s.object = object;
    s.piece = k;
    s.separation_m = separation;
}

// The slots of the carry-over table for a superset of `count` entries: a power of two at least
// twice the count (so probes stay short), as a mask.
inline uint32_t near_cache_table_mask(int count) {
    uint32_t n = 16;
    while (n < 2u * uint32_t(count) && n < uint32_t(kNearCacheHash)) n <<= 1;
    return n - 1;
}

// Indexes the entries of `pc` whose pose the ring still keeps by (object, triangle), in the slots
// `mask` gives (near_cache_table_mask of pc.count).
inline void near_cache_index(NearCache& c, const PieceNearCache& pc, uint32_t mask) {
    std::memset(c.table, 0xff, sizeof(int32_t) * (mask + 1));
    for (int i = 0; i < pc.count; ++i) {
        if (near_cache_slot(c, pc.entries[i].stamp) < 0) continue;
        uint32_t h = near_cache_hash(pc.object[i], pc.entries[i].tri) & mask;
        while (c.table[h] >= 0) h = (h + 1) & mask;
        c.table[h] = i;
    }
}

// The indexed entry of `pc` for (object, tri), or null.
inline const NearCacheEntry* near_cache_find(const NearCache& c, const PieceNearCache& pc, uint32_t mask,
                                             uint16_t object, uint32_t tri) {
    uint32_t h = near_cache_hash(object, tri) & mask;
    while (c.table[h] >= 0) {
        const NearCacheEntry& e = pc.entries[c.table[h]];
        if (e.tri == tri && e.object == object) return &e;
        h = (h + 1) & mask;
    }
    return nullptr;
}

}  // namespace sulcus
