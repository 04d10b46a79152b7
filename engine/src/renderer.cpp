// The servo step of the configuration-based renderer (seed paper sections II-IV), as named,
// timed stages:
//
//   detect  which object triangles the tool can reach this tick (BVH over the motion's bound),
//           and in free motion a conservative-advancement CCD from the last graphic pose to the
//           new haptic pose: when the whole motion is collision-free the graphic tool simply
//           follows the haptic tool.
//   gather  the principal contacts: for every tool vertex, object vertex and pair of edges in
//           reach, the object feature it faces (face, edge or vertex) is looked up and resolved
//           over the mesh adjacency by its convexity (Table 1): a face gives a V-F atom (eq. 6),
//           a concave edge or vertex the conjunction of its faces (eq. 8), a convex edge or vertex
//           the one face the tool is in front of -- with the other faces as candidates when tied;
//           convex object vertices give F-V atoms against the tool face they are outside of, and
//           convex object edges E-E atoms on the dynamic plane of eq. 7.
//   solve   for each candidate set, the QP of eq. 1-5 in the rotation-vector coordinates about
//           the last graphic pose, re-linearized until every atom holds exactly within
//           constraint_tol_m; an exact separating-axis check of every triangle in reach guards
//           the result and adds the separating plane of any triangle the atoms missed.
//   select  the feasible candidate of least energy (eq. 3): the local solution.
//   force   eq. 4.
#include "sulcus/engine/renderer.h"

#include "capsule_bounds.h"
#include "ccd.h"
#include "contact_atoms.h"
#include "near_cache.h"
#include "radix_sort.h"
#include "geometry.h"
#include "lanes.h"
#include "so3.h"
#include "tool_placement.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>

namespace sulcus {

const char* to_string(StepStatus s) {
    switch (s) {
        case StepStatus::Free: return "free";
        case StepStatus::Contact: return "contact";
        case StepStatus::Partial: return "partial";
        case StepStatus::Held: return "held";
        case StepStatus::BadInput: return "bad_input";
    }
    return "unknown";
}

State make_state(const Pose& pose) {
    static std::atomic<uint64_t> sessions{0};
    State s;
    s.session = ++sessions;
    s.graphic = pose;
    s.graphic.orientation = glm::normalize(pose.orientation);
    s.last_haptic = s.graphic;
    s.initialized = true;
    return s;
}

void compute_wrench(const HapticSettings& h, const Pose& graphic, const Pose& haptic, Vec3& force_N,
                    Vec3& torque_Nm) {
    // eq. 4: F = K_e (q_g - q_h); the rotational difference as a world rotation vector.
    force_N = h.stiffness_N_per_m * (graphic.position - haptic.position);
    torque_Nm = h.rotational_stiffness_Nm_per_rad *
                quat_log(graphic.orientation * glm::conjugate(haptic.orientation));
}

void near_cache_measure_motion(NearCache& c, const Model& model, int slot, size_t k) {
    c.motion_m[slot][k] = motion_bound_turned(model.tool.pieces[k], c.ring[slot], c.ring[c.stamp % kNearCacheSlots],
                                              near_cache_turn(c, slot));
    c.motion_for[slot][k] = c.stamp;
}

void near_cache_measure_origin(NearCache& c, int slot) {
    const Vec3 shift = c.ring[c.stamp % kNearCacheSlots].position - c.ring[slot].position;
    c.origin_shift[slot] = shift;
    c.origin_move[slot] = glm::length(shift);
    c.origin_turn[slot] = near_cache_turn(c, slot);
    c.origin_for[slot] = c.stamp;
}

namespace {

using Clock = std::chrono::steady_clock;

double micros(Clock::time_point a, Clock::time_point b) {
    return std::chrono::duration<double, std::micro>(b - a).count();
}

constexpr int kMaxToolVertices = 4096;
constexpr int kMaxToolFaces = 4096;
constexpr int kMaxToolEdges = 3 * kMaxToolVertices;
static_assert(kMaxToolVertices <= 4096, "a feature key keeps its tool vertex in 12 bits (packed_feature)");
static_assert(kMaxToolEdges <= 65536, "a piece's edges are counted in 16 bits (Workspace::edge_hits, EdgeHitMemo::hits)");
static_assert(kToolCapsules <= 16, "Bvh::query_capsule_chain takes at most 16 capsules");
constexpr int kMaxNear = 8192;
// How far a compliant set's capsules may move before a triangle is measured again (m;
// gather_in_box).
constexpr double kRemeasureMotion = 3e-5;
// How far past the tests' bounds gather_atoms looks for a piece's vertices when it measures how
// long a triangle stays clear of them (m; Workspace::CompliantSet::quiet).
constexpr double kQuietHorizon = 5e-5;
// A triangle of a compliant set with no feature whose nearest vertex is this close to the bounds
// (m) is listed (Workspace::CompliantSet::listed), not passed over until the drift reaches it:
// the listed vertices are cheaper to look at each tick than the whole search so soon again.
constexpr double kListedClearance = 0.1 * kQuietHorizon;
constexpr int kMaxAtoms = 1024;
// Triangles the guard finds the atoms let the tool into, taken in one round: all of them as a
// rule (deep in the tissue some sixty at once), so that the candidate is solved again once.
constexpr int kMaxMissed = 64;
constexpr int kMaxFeatures = 4096;  // tool vertices against object features, per gather
constexpr int kMaxObjFeatures = 3 * kMaxNear;  // object vertices or edges: three per near triangle
constexpr int kMaxAlts = 32;
constexpr int kMaxHalvings = 6;
constexpr int kMaxCcdIterations = 64;
constexpr int kMaxPasses = 6;
// A tool vertex more than this behind a face plane does not face it (it is across a thin part).
constexpr double kBackFace = 1e-6;
// The recovery round's box gives every coordinate this many constraint tolerances of room to
// take the tool back out of a graze (local_box's `recover_m`).
constexpr double kRecoverTolerances = 10.0;
// How far behind an object's face or edge a tool feature still faces it: kBackFace on a compliant
// object (gather adds the tool's depth in it); on a rigid one kBackFace, or the room the recovery
// round has (kRecoverTolerances tolerances) where that is less. The step's
// start is a checked pose, so a feature pair further behind than that there is not a graze the
// step can take the tool out of: a pair across a thin part, or one whose constraint says the
// tool is behind where it does not penetrate (on the dense wedge at 1e-9 m: edge pairs 0.36 um
// behind at a start the exact check finds 3e-17 m deep). Held as a constraint, it leaves no
// feasible step, and the tool is held where it is. From the default tolerance (1e-7 m) up, this
// is kBackFace.
double back_face(const RendererSettings& S, bool compliant) {
    return compliant ? kBackFace : std::min(kBackFace, kRecoverTolerances * S.constraint_tol_m);
}

using NearTri = NearTriangle;

// A tool vertex facing an object feature: type 0 face (id = triangle), 1 edge, 2 vertex.
struct FeatureKey {
    uint32_t a;
    uint16_t object;
    uint8_t type;
    uint32_t id;
    bool operator<(const FeatureKey& o) const {
        if (a != o.a) return a < o.a;
        if (object != o.object) return object < o.object;
        if (type != o.type) return type < o.type;
        return id < o.id;
    }
    bool operator==(const FeatureKey& o) const {
        return a == o.a && object == o.object && type == o.type && id == o.id;
    }
};

// A key as one number in the same order: the tool vertex in the top 12 bits (kMaxToolVertices),
// then the object, the type (0-2) and the feature's id. Sorted so, the keys sort as
// FeatureKey::operator< sorts them.
inline uint64_t packed_feature(const FeatureKey& k) {
    return uint64_t(k.a) << 52 | uint64_t(k.object) << 36 | uint64_t(k.type) << 32 | k.id;
}
inline FeatureKey unpacked_feature(uint64_t p) {
    return FeatureKey{uint32_t(p >> 52), uint16_t(p >> 36), uint8_t(p >> 32 & 0xfu), uint32_t(p)};
}

// A tool vertex facing a feature of a compliant object: its height over the triangle's plane,
// whether it is inside (behind the face, over it), and how far the face's normal points along the
// object's push.
struct Inside {
    FeatureKey key;
    double plane;
    double distance;  // from the tool vertex to the triangle
    bool behind;
    double facing;
};

// An object vertex or edge near a piece of the tool, packed so that the keys sort by object,
// then feature, then piece.
using ObjFeature = uint64_t;
inline ObjFeature obj_feature(uint16_t object, uint32_t id, uint8_t piece) {
    return uint64_t(object) << 40 | uint64_t(id) << 8 | piece;
}
inline uint16_t feature_object(ObjFeature f) { return uint16_t(f >> 40); }
inline uint32_t feature_id(ObjFeature f) { return uint32_t(f >> 8); }
inline uint8_t feature_piece(ObjFeature f) { return uint8_t(f); }

// An alternative principal contact: atoms[replace] swapped for `atom`.
struct Alt {
    int replace;
    Atom atom;
};

// Slack variables of a candidate: one per spring of every compliant zone its atoms touch, after
// the six pose variables of the QP.
inline constexpr int kMaxSlackVars = qp::kMaxVars - qp::kPoseVars;

struct Slacks {
    int zones = 0;
    uint16_t zone[kMaxSlackVars] = {};
    int first[kMaxSlackVars] = {};  // QP variable of the zone's first spring
    int count[kMaxSlackVars] = {};
    double depth[kMaxSlackVars] = {};  // how far the zone gives way at the solution (m)
    int vars = qp::kPoseVars;          // QP variables in use
};

// Active contacts of a solution as friction needs them: unit normal (world, translation part of
// the constraint's gradient), normal force and the Coulomb coefficients of their material.
struct FrictionContacts {
    int count = 0;
    Vec3 normal[qp::kMaxVars];
    double force_N[qp::kMaxVars] = {};
    double mu_static[qp::kMaxVars] = {};
    double mu_kinetic[qp::kMaxVars] = {};
};

struct CandidateResult {
    bool ok = false;
    double x[6] = {0, 0, 0, 0, 0, 0};
    double energy = 0.0;
    double spring_energy_J = 0.0;  // the compliant zones' springs' energy at the answer, in joules
    double error = 0.0;
    int relinearizations = 0;
    int atom_count = 0;
    // The answer is the first QP's since the step's start (or since the guard last added planes):
    // its rows are linearized at x = 0, as every candidate's first QP is.
    bool from_start = false;
    // A bound of the box on a pose coordinate holds the answer (active with a multiplier).
    bool box_held = false;
};

// Scratch memory of the step: allocated once per thread, reused every tick.
struct Workspace {
    Vec3 tool_world[kMaxToolVertices];
    Vec3 tool_moved[kMaxToolVertices];
    uint16_t edge_hits[kMaxToolEdges];  // tool edges near one object edge, from the piece's first
    uint16_t edge_open[kMaxToolEdges];  // those of them closest_at_an_end leaves open, likewise
    Vec3 face_n[kMaxToolFaces];
    double face_d[kMaxToolFaces];
    double face_s[kMaxToolFaces];  // gather: an object vertex's height over each face of a piece (m)
    // The pose face_n, face_d and capsule were placed at (rotation, position), for a model
    // (Model::serial; 0: none).
    Quat face_q{1.0, 0.0, 0.0, 0.0};
    Vec3 face_p{0.0};
    uint64_t planes_model = 0;
    Vec3 capsule[kMaxToolPieces * (kToolCapsules + 1)];  // the pieces' bounding capsules at that pose
    // The same at the pose a solve moves the tool to (the guard's check there).
    Vec3 moved_face_n[kMaxToolFaces];
    double moved_face_d[kMaxToolFaces];
    Quat moved_face_q{1.0, 0.0, 0.0, 0.0};
    Vec3 moved_capsule[kMaxToolPieces * (kToolCapsules + 1)];
    NearTri near[kMaxNear];
    int near_count = 0;
    // Whether `near` holds every triangle within each piece's reach `near_reach` of it at the
    // pose detect ran at (the pass's base; the last detect was complete, not narrowed from an
    // earlier one).
    bool near_complete = false;
    PieceReach near_reach[kMaxToolPieces];
    // A complete near set of an earlier pass of the tick, which a later pass narrows where it
    // covers the pass's box (prior_* as near_* above).
    NearTri prior[kMaxNear];
    int prior_count = 0;
    Pose prior_pose;
    PieceReach prior_reach[kMaxToolPieces];
    int tests = 0;  // triangle tests of this tick (StepStats::triangles_tested)
    int compliant_gathers = 0;  // StepStats::compliant_gathers
    int bounds_measured = 0;    // tissue triangles' bounds measured in this tick (gather_in_box)
    int quiet_triangles = 0;    // StepStats::quiet_triangles
    int edge_queries = 0;       // StepStats::edge_queries
    int edge_memos_ahead = 0;   // StepStats::edge_memos_ahead
    int face_searches = 0;      // StepStats::face_searches
    int quiet_featured = 0;     // StepStats::quiet_featured
    int detect_tests = 0;  // detect's distance tests of this tick (judge_near)
    FeatureKey feats[kMaxFeatures];
    int feat_count = 0;
    uint64_t feat_keys[kMaxFeatures];  // feats packed (packed_feature), for their sort
    bool gather_full = false;  // an atom or feature of this gather did not fit
    Inside inside[kMaxFeatures];
    int inside_count = 0;
    // The same in key order (by tool vertex, then object and feature), and where each tool
    // vertex's run begins in it.
    Inside inside_sorted[kMaxFeatures];
    int inside_first[kMaxToolVertices + 1];
    ObjFeature overts[kMaxObjFeatures];
    int overt_count = 0;
    ObjFeature oedges[kMaxObjFeatures];
    ObjFeature feature_scratch[kMaxObjFeatures];
    DedupeTable feature_table;
    int oedge_count = 0;
    Atom atoms[kMaxAtoms];
    int atom_count = 0;
    Alt alts[kMaxAlts];
    int alt_count = 0;
    Atom cand[kMaxAtoms];
    int cand_count = 0;
    // The separating planes' atoms the guard adds, in the order it adds them: the default
    // candidate's come first, and every other candidate starts with them.
    Atom planes[kMaxAtoms];
    int plane_count = 0;
    Atom best[kMaxAtoms];
    int best_count = 0;
    // The (triangle, piece) pair a separating plane's atom was made for (plane_key), 0 for a
    // gathered atom: cand_key, planes_key and best_key run with cand, planes and best.
    uint64_t cand_key[kMaxAtoms];
    uint64_t planes_key[kMaxAtoms];
    uint64_t best_key[kMaxAtoms];
    bool best_box_held = false;  // a bound of the box holds the chosen candidate's answer
    double best_energy = 0.0;    // the chosen candidate's energy (eq. 3, with its springs')
    double best_spring_energy_J = 0.0;  // the springs' share of it, in joules
    // Compliance of the candidate being solved and of the best one: each atom's slack zone
    // (-1: rigid) and the zones' slacks.
    int8_t cand_slot[kMaxAtoms];
    // Reordering a candidate whose atoms outnumber the QP's rows.
    Atom order_atoms[kMaxAtoms];
    int8_t order_slots[kMaxAtoms];
    uint64_t order_keys[kMaxAtoms];
    double order_value[kMaxAtoms];
    int order_index[kMaxAtoms];
    // Gather's V-F and separating-plane atoms at the base (cover_zones): their values, zone slots,
    // and where each moves to when the covered ones drop.
    double atom_value[kMaxAtoms];
    int8_t atom_zone_slot[kMaxAtoms];
    int atom_moved_to[kMaxAtoms];
    // gather: the object feature (ObjFeature) each F-V or E-E atom was made for, and the F-V
    // atoms' alternatives as they were made, until both are put in the features' order
    // (order_by_feature).
    uint64_t atom_feature[kMaxAtoms];
    Alt alt_made[kMaxAtoms];
    int alt_made_count = 0;
    Slacks slacks;
    int8_t best_slot[kMaxAtoms];
    // How deep the tool is in each compliant object at the base of the pass, and its springs'
    // energy: the state's at the first, the earlier pass's answer's after.
    SoftDepths soft;
    Slacks best_slacks;
    FrictionContacts friction, best_friction;
    qp::Problem problem;
    qp::Solution solution;
    qp::WarmStart warm;
    NearCache cache;
    // The axis the last separating-axis test of a (piece, triangle) pair found, by a hash of the
    // pair (key 0: none), kept along a session as the near cache is: the guard tries it before
    // testing the pair again.
    struct SatMemo {
        uint64_t key = 0;
        Vec3 axis{0.0};
    };
    // 4,096 slots: in the tissue some 800 gingiva triangles are near the probe, and 256 slots
    // lost the axes of most of those the guard tests tick after tick.
    static constexpr int kSatMemoBits = 12;
    static constexpr int kSatMemo = 1 << kSatMemoBits;
    SatMemo sat_memo[kSatMemo];
    // Where the witnesses' last look found each piece's least and greatest vertex along its axis:
    // the next one's descents start there (neighbouring triangles have nearly the same normal).
    int gap_extremes[kMaxToolPieces][2] = {};
    // The face of each piece that last showed the guard a triangle vertex not deep inside it.
    int deep_rejecting[kMaxToolPieces] = {};
    // The near triangles the guard checks at the new pose (indices into `near`, in order), and
    // the give of each one's zone there: those the pass over the start leaves unsettled.
    int guard_open[kMaxNear];
    double guard_give[kMaxNear];
    // The tool edges (relative to their piece's first) within `far` plus a room (edge_memo_room)
    // of an object edge in the piece's frame, by a hash of the (object, edge, piece) feature plus
    // one (key 0: none), for a session (Workspace::owner): while neither end of the edge has moved
    // by more than the room less the rise of `far`, every other tool edge stays further than
    // `far` from it, where no pair makes an atom. A key sits in its hash slot or the one beside
    // it (slot ^ 1): of a pair of edges in the tissue that share a slot, neither pushes the other
    // out at every tick, as they did in a table of one slot a key and a quarter the size. Up to
    // 160 hits: a probe deep in an inflamed floor looks a millimetre round each edge, which then
    // holds more than half the tip's edges within reach (40 hits kept those edges out, and each
    // went to the hierarchy and a sort at every tick).
    static constexpr int kEdgeMemoHits = 160;
    struct EdgeHitMemo {
        uint64_t key = 0;
        uint64_t owner = 0;  // Workspace::owner
        uint64_t used = 0;  // gather_clock at the last use
        Vec3 at[2]{Vec3(0.0), Vec3(0.0)};  // the object edge's ends in the piece's frame at the query
        double far = 0.0;                  // the edge's `far` at the query
        int count = 0;
        uint16_t hits[kEdgeMemoHits];
        // Holds the `n` hits at `from` (at most kEdgeMemoHits), found with the edge's ends at l0,
        // l1 and its `far` (edge_memo_within).
        void hold(const Vec3& l0, const Vec3& l1, double far_m, const uint16_t* from, int n) {
            at[0] = l0;
            at[1] = l1;
            far = far_m;
            count = n;
            std::copy(from, from + n, hits);
        }
    };
    static constexpr int kEdgeMemoBits = 12;
    EdgeHitMemo edge_memo[1 << kEdgeMemoBits];
    // The memos the last gather_atoms call used that had moved past kEdgeRenewShare of their
    // slack, with what a query at that call would take (the edge's ends in the piece's frame and
    // its `far`): tend_edge_memos makes some of them anew at the tick's end, ahead of need.
    struct EdgeDue {
        EdgeHitMemo* memo;  // holds `key` still unless a later edge of that call took its slot
        uint64_t key;
        Vec3 at[2];
        double far;
        double share;  // the larger end's motion over the memo's slack
    };
    static constexpr int kEdgeDue = 256;
    EdgeDue edge_due[kEdgeDue];
    int edge_due_count = 0;
    uint64_t gather_clock = 0;  // counts gather_atoms' calls
    // The most room a memo's hits reach past `far` (m): in the tissue, where an edge's reach is the
    // tool's depth in it, a room of all of that holds more hits than a memo keeps.
    static constexpr double kEdgeMemoRoom = 1e-4;
    // How far past `far` (m) an edge memo's hits reach: `far`, at most kEdgeMemoRoom.
    static double edge_memo_room(double far) { return std::min(far, kEdgeMemoRoom); }
    // How far from an edge of `far` a memo's hits are taken: its room over, and a nanometre for
    // the rounding of the frames.
    static double edge_memo_within(double far) { return far + edge_memo_room(far) + 1e-9; }
    // The triangles of a compliant object near a piece, kept between ticks (with the near
    // cache): the slots (Bvh::query_slots) whose boxes overlap `box`, the piece's query box of
    // some tick widened by kCompliantRoom. While a later query box lies inside it, that query's
    // triangles are these slots filtered by their boxes, in the same order, without the walk
    // down the hierarchy. For (object, piece) of a model; kCompliantSets of them, the one used
    // longest ago replaced. For a session (Workspace::owner).
    //
    // Each slot keeps the capsules' bound on its triangle (piece_compliant_bound) where it was
    // last measured, as that bound plus the set's `moved` then. `moved` adds up how far the
    // piece's capsule points have moved at each query since the set was made (from `axis`, where
    // they were at the last one): no capsule is nearer a triangle now than its bound then less
    // what `moved` has grown by since. A triangle that this puts beyond what gather looks at is
    // not measured again (gather_in_box).
    //
    // Each slot also keeps how long its triangle stays clear of gather_atoms' tests of the piece's
    // vertices (none in the band of its plane nor within `far` of it): `quiet`, in terms of the
    // set's `drift`, which adds up at each gather how far the piece's vertices may have moved
    // since the last (motion_bound) and how much the tests' bounds have widened (twice the rise
    // of the reach, once the rise of the tool's depth in the object). While `drift` is below
    // `quiet` no vertex can have come into the tests' bounds, and the triangle gives no V-F
    // feature without being looked at. NearTriangle::memo names the set and slot of a triangle
    // a set gave (kMemoSlotBits).
    static constexpr int kCompliantSets = 8;
    static constexpr int kCompliantSetSlots = 4096;
    static constexpr double kCompliantRoom = 1e-4;
    static constexpr int kMemoSlotBits = 12;
    static_assert(kCompliantSetSlots == 1 << kMemoSlotBits && kCompliantSets < (1 << (16 - kMemoSlotBits)),
                  "a set's slot and the set's index plus one fit NearTriangle::memo");
    // `quiet` of a triangle whose vertices' clearance is not known (looked at with a margin the
    // next time), and of one that gave a feature the last time (looked at without one).
    static constexpr double kQuietUnknown = -1e300;
    static constexpr double kQuietNone = -std::numeric_limits<double>::infinity();
    struct CompliantSet {
        uint64_t owner = 0;  // Workspace::owner; 0: empty
        uint16_t object = 0;
        uint8_t piece = 0;
        uint64_t used = 0;
        Aabb box;
        int count = 0;
        uint32_t slots[kCompliantSetSlots];
        double kept[kCompliantSetSlots];  // bound + moved when measured (m); -1e300: not measured
        double measured_at[kCompliantSetSlots];  // `moved` when measured (m)
        double quiet[kCompliantSetSlots];  // m, in terms of `drift`; or kQuietUnknown, kQuietNone
        // Of a triangle that gave a feature, the piece's vertices (bits by their place in its
        // axial order) that may come within the bounds while the drift is under `quiet`; 0: none.
        uint64_t listed[kCompliantSetSlots];
        Vec3 axis[kToolCapsules + 1];     // the capsule points at the last query (world)
        double moved = 0.0;               // m
        Aabb query;                       // the last query's box
        double drift = 0.0;               // m
        // The gather_atoms call (Workspace::gather_clock) the fields below are of; 0: none.
        uint64_t drift_call = 0;
        Pose drift_pose;                  // the tool's base pose at that call
        double drift_reach = 0.0;         // its reach (m)
        double drift_depth = 0.0;         // the tool's depth in the object then (SoftDepths, m)
    };
    CompliantSet compliant_sets[kCompliantSets];
    // A set's old slots and quiet marks while it is gathered anew (gather_compliant_set).
    uint32_t carry_slots[kCompliantSetSlots];
    double carry_quiet[kCompliantSetSlots];
    uint64_t carry_listed[kCompliantSetSlots];
    uint64_t compliant_clock = 0;
    // The faces of a piece that an object vertex could be most in front of, or within the tie
    // tolerance of it, while it stays within `room` of where they were found (`at`, m, in the
    // piece's frame): those within twice the room and the tie tolerance of the most there; or
    // (count -1) the face that put it beyond the reach, faces[0]. By a hash of the (object,
    // vertex, piece) feature plus one (key 0: none), for a session (Workspace::owner).
    static constexpr int kFaceMemoFaces = 16;
    struct FaceMemo {
        uint64_t key = 0;
        uint64_t owner = 0;  // Workspace::owner
        Vec3 at{0.0};
        double room = 0.0;
        int count = 0;
        uint16_t faces[kFaceMemoFaces];
    };
    static constexpr int kFaceMemoBits = 10;
    FaceMemo face_memo[1 << kFaceMemoBits];
    // Whose the tissue sets and the edge and face memos are: the model's (Model::serial) and the
    // session's (State::session), never 0 (an empty set's or memo's). A new session starts them
    // afresh, as it does the near cache: what a step costs then does not depend on the sessions
    // stepped before it (the bench's runs each from a fresh state). Sessions stepped in turns
    // keep theirs apart.
    uint64_t owner = 0;
};

// When a tissue set or an edge memo was last used, for replacing the one used longest ago: one
// of another owner's (Workspace::owner) counts as never used.
template <class Entry>
uint64_t last_use(const Entry& e, uint64_t owner) {
    return e.owner == owner ? e.used : 0;
}

Workspace& workspace() {
    thread_local std::unique_ptr<Workspace> ws = std::make_unique<Workspace>();
    return *ws;
}

// The energy a caller of solve_candidate can take: an answer with more than `any`, or with
// more than `virtual_answer` while some contact of it is virtual, is of no use to it.
struct EnergyLimit {
    double any = std::numeric_limits<double>::infinity();
    double virtual_answer = std::numeric_limits<double>::infinity();
};

double energy_of(const HapticSettings& h, const double x[6], const double target[6]) {
    double e = 0.0;
    for (int j = 0; j < 3; ++j) e += h.weight_translational * (x[j] - target[j]) * (x[j] - target[j]);
    for (int j = 3; j < 6; ++j) e += h.weight_rotational * (x[j] - target[j]) * (x[j] - target[j]);
    return 0.5 * e;
}

// eq. 3's energy of pose x for the target with the zones' springs (spring variables x[6, vars)
// weighted as in P), and the springs' part of it.
double energy_with_springs(const HapticSettings& h, const qp::Problem& P, const double* x, const double target[6],
                           int vars, double* springs_out = nullptr) {
    double springs = 0.0;
    for (int v = qp::kPoseVars; v < vars; ++v) springs += 0.5 * P.weight[v] * x[v] * x[v];
    if (springs_out) *springs_out = springs;
    return energy_of(h, x, target) + springs;
}

ConvexView tool_view(const Model& model, size_t piece, const Vec3* world_vertices, const Workspace& w) {
    return tool_convex_view(model.tool, piece, world_vertices, w.face_n, w.face_d, &w.face_q, w.capsule);
}

void set_tool_planes(const Model& model, const Quat& q, const Vec3& p, Workspace& w) {
    // Already there (to the bit) for this model: mostly where a tick in contact placed them at its
    // graphic pose (for the contact regions), which is the next tick's start.
    if (model.serial != 0 && w.planes_model == model.serial && std::memcmp(&w.face_q, &q, sizeof(Quat)) == 0 &&
        std::memcmp(&w.face_p, &p, sizeof(Vec3)) == 0)
        return;
    place_tool_planes(model.tool, q, p, w.face_n, w.face_d);
    place_tool_capsule(model.tool, q, p, w.capsule);
    w.face_q = q;
    w.face_p = p;
    w.planes_model = model.serial;
}

double box_reach(const RendererSettings& S, double tool_radius, const double lower[6], const double upper[6]);

// A lower bound on the distance between a piece with capsules and triangle (a, b, c) of normal n:
// the least over its capsules of the bounding-sphere bound, raised where a capsule's axis lies
// wholly on one side of the triangle's plane to its nearer end's height (least_over_capsules).
// `nearest` receives the capsule that gave it.
double piece_capsule_bound(const ToolPiece& piece, const CapsuleLine& line, const Vec3& a, const TriangleSphere& ts,
                           const Vec3& n, int& nearest) {
    const Vec3* axis = line.axis;
    auto capsule = [&](int j) {
        const double r = piece.capsule_radii_m[size_t(j)];
        double bj = capsule_sphere_lower(axis[j], axis[j + 1], r, ts);
        const double h0 = glm::dot(n, axis[j] - a), h1 = glm::dot(n, axis[j + 1] - a);
        if (h0 * h1 > 0.0) bj = std::max(bj, std::min(std::abs(h0), std::abs(h1)) - r);
        return bj;
    };
    return least_over_capsules(piece, line, ts, capsule, nearest);
}

// The least over a piece's tapered capsules (ToolPiece::taper_radii_m) of their tangent bound on
// the distance to triangle (a, b, e) of bounding sphere ts: tighter than the capsules' on a
// tapering probe, and dearer. Above zero, the triangle is that far from the piece at least.
double piece_taper_bound(const ToolPiece& piece, const CapsuleLine& line, const TriangleSphere& ts, const Vec3& a,
                         const Vec3& b, const Vec3& e) {
    int nearest = 0;
    return least_over_capsules(
        piece, line, ts,
        [&](int j) {
            const auto& taper = piece.taper_radii_m[size_t(j)];
            return taper_tangent_lower(line.axis[j], line.axis[j + 1], taper[0], taper[1], ts, a, b, e);
        },
        nearest);
}

// Whether a triangle of a rigid object is within `reach` of piece k (which has capsules), and
// bounds [lo, hi] on their distance: the capsules' bound first, then GJK from the nearest
// capsule's axis to within `tol`; where rounding stalls GJK short of a verdict, the exact
// distance. With `capsules_only`, the capsules' word.
struct NearVerdict {
    bool keep = false;
    double lo = 0.0;
    double hi = 1e300;
    Vec3 direction{0.0};
    GjkSimplex simplex{};
    double direction_gap = -1e300;  // DistanceBounds::direction_gap
};

NearVerdict judge_near(const Model& model, size_t k, const ConvexView& view, const CapsuleLine& line,
                       const ModelObject& obj, uint32_t tri, double reach, double tol, bool capsules_only,
                       double cutoff = 0.0, const Vec3* start = nullptr, const GjkSimplex* warm = nullptr) {
    const ToolPiece& piece = model.tool.pieces[k];
    const Vec3* axis = line.axis;
    const auto& t = obj.mesh.triangles[tri];
    const Vec3 &a = obj.mesh.vertices[t[0]], &b = obj.mesh.vertices[t[1]], &c = obj.mesh.vertices[t[2]];
    int nearest = 0;
    const double bound = piece_capsule_bound(piece, line, a, obj.topology.triangle_spheres[tri],
                                             obj.topology.triangle_normals[tri], nearest);
    if (bound > reach) return NearVerdict{false, bound, 1e300};
    if (capsules_only) return NearVerdict{true, bound, 1e300};
    // GJK starts along the line from the triangle to the nearest capsule's axis.
    const Vec3 centre = (a + b + c) / 3.0, d = axis[nearest + 1] - axis[nearest];
    const double dd = glm::dot(d, d);
    const double s = dd > 0.0 ? std::clamp(glm::dot(centre - axis[nearest], d) / dd, 0.0, 1.0) : 0.0;
    const Vec3 hint = start && glm::dot(*start, *start) > 0.0 ? *start : axis[nearest] + s * d - centre;
    DistanceBounds g = convex_triangle_distance(view, a, b, c, std::max(reach, cutoff), tol, 64, &hint, warm);
    if (g.lower <= reach && g.upper - g.lower > tol) {
        g.lower = g.upper = distance_convex_triangle_by_faces(view, piece_triangles(model.tool, k),
                                                              int(piece.triangle_count), a, b, c);
    }
    return NearVerdict{g.lower <= reach, std::max(bound, g.lower), g.upper, g.direction, g.simplex, g.direction_gap};
}

// How much further than the tick's reach a piece's superset reaches: the tool can move that far
// before the superset is gathered again.
double superset_margin(double reach) { return std::max(2e-4, 3.0 * reach); }

// Starts gathering piece k's next superset at pose `at` (its capsules `axis` placed there):
// every triangle of the rigid objects the capsules' bound puts within `radius`.
void start_superset(NearCache& c, size_t k, const Pose& at, const Vec3* axis, double radius) {
    SupersetBuild& b = c.build;
    b.active = true;
    b.piece = k;
    b.pose = at;
    b.stamp = c.stamp;
    b.path_m = c.path_m[k];
    b.radius_m = radius;
    for (int j = 0; j <= kToolCapsules; ++j) b.axis[j] = axis[j];
    b.object = 0;
    b.walking = false;
    b.count = 0;
}

// Walks the superset in progress on for `budget` (boxes and triangles looked at); true when it
// is complete. One that outgrows kNearCacheEntries is dropped.
bool advance_superset(const Model& model, NearCache& c, long budget) {
    SupersetBuild& b = c.build;
    const ToolPiece& piece = model.tool.pieces[b.piece];
    const CapsuleLine line = capsule_line(piece, b.axis);
    for (; b.object < model.objects.size(); ++b.object, b.walking = false) {
        const ModelObject& obj = model.objects[b.object];
        if (obj.compliant) continue;
        if (!b.walking) {
            b.walk.start(b.axis, piece.capsule_radii_m.data(), piece.capsule_count, b.radius_m);
            b.walking = true;
        }
        const uint16_t ok = static_cast<uint16_t>(b.object);
        bool overflow = false;
        const bool done = obj.bvh.walk_capsule_chain(b.walk, budget, [&](uint32_t tri) {
            int nearest = 0;
            const double bound = piece_capsule_bound(piece, line, obj.mesh.vertices[obj.mesh.triangles[tri][0]],
                                                     obj.topology.triangle_spheres[tri],
                                                     obj.topology.triangle_normals[tri], nearest);
            if (bound > b.radius_m) return true;
            if (b.count >= kNearCacheEntries) {
                overflow = true;
                return false;
            }
            NearCacheEntry& e = b.entries[b.count++];
            e = NearCacheEntry{};
            e.tri = tri;
            e.object = ok;
            e.stamp = b.stamp;
            e.path_m = b.path_m;
            e.lo = bound;
            return true;
        });
        if (overflow) {
            b.active = false;
            return false;
        }
        if (!done) return false;
    }
    return true;
}

// Makes the completed superset its piece's, each entry with the bounds the old superset had for
// its triangle where they still hold: both where the old ones were measured (GJK), else whichever
// lower bound is higher now, the old superset's or the capsules' bound where the new one was
// gathered. (A triangle the old superset found far by the capsules' bound or GJK's first gap
// alone has no upper bound; its lower bound is usually fresher than the build's.)
void install_superset(const Model& model, NearCache& c) {
    SupersetBuild& b = c.build;
    PieceNearCache& pc = c.piece[b.piece];
    // The old entries whose pose is still kept, found by triangle; the new ones take over theirs
    // in place, then become the piece's.
    if (!pc.valid) pc.count = 0;
    const uint32_t mask = near_cache_table_mask(pc.count);
    near_cache_index(c, pc, mask);
    double built_motion = 0.0;
    const bool built_known = near_cache_motion(c, model, b.stamp, b.piece, built_motion);
    // When each entry needs a look (PieceNearCache::due): by its lower bound and the path where
    // that held, or the old entry's due where that is later (both bound the distance from below
    // along the same path), so that the far entries of a new superset are not all read at once.
    for (int i = 0; i < b.count; ++i) {
        NearCacheEntry& e = b.entries[i];
        const NearCacheEntry* p = near_cache_find(c, pc, mask, e.object, e.tri);
        double m = 0.0;
        const double old_due = p ? pc.due[p - pc.entries] : -1e300;
        if (p && (p->hi < 1e300 || !built_known ||
                  (near_cache_motion(c, model, p->stamp, b.piece, m) && p->lo - m > e.lo - built_motion)))
            e = *p;
        b.due[i] = std::max(old_due, e.lo + e.path_m);
    }
    std::swap(pc.entries, b.entries);
    std::swap(pc.due, b.due);
    for (int i = 0; i < b.count; ++i) pc.object[i] = pc.entries[i].object;
    pc.count = b.count;
    pc.valid = true;
    pc.pose = b.pose;
    pc.radius_m = b.radius_m;
    b.active = false;
}

// Work per tick on a superset in progress (boxes and triangles looked at): about 15 us.
constexpr long kSupersetSlice = 384;
// Distance tests in detect that make a tick heavy (tend_superset): about a tenth of the ticks in
// contact on the bench's dense wedge have more.
constexpr int kHeavyDetectTests = 64;
// Triangles tested in the whole tick that leave room for a double slice: about half the ticks
// in contact on the dense wedge test fewer, and cost under 0.6 M instructions (p99) with it.
constexpr int kLightTests = 40;
// Work that comes in bursts and makes a tick heavy (tend_superset, tend_compliant_sets): tissue
// bounds measured (a tissue set gathered anew has some 700 measured at the next tick, and again
// as they fall due together kRemeasureMotion on), and edge memos made anew (a crown's edges in a
// fast stroke, some 50-90 at once).
constexpr int kHeavyBoundsMeasured = 256;
constexpr int kHeavyEdgeQueries = 32;
// Edge memos made at one tick run out at one tick (some 50-90 of a crown's or the tissue's edges
// in a stroke). One that a tick used after moving past this share of its slack is made anew at
// the tick's end, ahead of need (tend_edge_memos): up to kEdgeRenewPerTick a tick, and on a heavy
// one only those past kEdgeRenewUrgent, up to kEdgeRenewPerHeavyTick.
constexpr double kEdgeRenewShare = 0.5;
constexpr double kEdgeRenewUrgent = 0.75;
constexpr int kEdgeRenewPerTick = 24;
constexpr int kEdgeRenewPerHeavyTick = 8;

// Piece k's superset for a tick of reach `reach` at pose `at` (capsules `axis`): the current one
// while it holds, the one in progress once complete, and a new one gathered at once when neither
// holds. A new one is started once the tool has used a quarter of the margin, and gathered in
// slices at the ends of ticks (tend_superset). Null when a superset does not fit (the caller measures
// from scratch).
PieceNearCache* piece_superset(const Model& model, NearCache& c, size_t k, const Pose& at, const Vec3* axis,
                               double reach, double tol) {
    PieceNearCache& pc = c.piece[k];
    SupersetBuild& b = c.build;
    const ToolPiece& piece = model.tool.pieces[k];
    const double need = reach + tol, margin = superset_margin(reach);
    // How much further than the need a superset gathered at `from` still reaches (< 0: it does not hold).
    auto room = [&](const Pose& from, double radius) { return radius - need - motion_bound(piece, from, at); };
    double current = pc.valid ? room(pc.pose, pc.radius_m) : -1.0;
    if (b.active && b.piece == k) {
        if (!(room(b.pose, b.radius_m) > 0.0)) {
            b.active = false;  // the tool went past it: dropped
        } else if (!(current > 0.0) && advance_superset(model, c, std::numeric_limits<long>::max())) {
            install_superset(model, c);
            current = room(pc.pose, pc.radius_m);
        }
    }
    if (current > 0.0) {
        pc.room_m = current;
        pc.margin_m = margin;
        if (!b.active && current < 0.75 * margin) start_superset(c, k, at, axis, need + margin);
        return &pc;
    }
    start_superset(c, k, at, axis, need + margin);
    if (!advance_superset(model, c, std::numeric_limits<long>::max())) {
        pc.valid = false;
        return nullptr;
    }
    install_superset(model, c);
    return &pc;
}

// An edge memo's hits made anew: the tool edges of `piece` (relative to its first) within
// `within` of the object edge l0-l1 in the piece's frame, in their order, into `out`; the count.
int edge_hits_within(const ModelTool& tool, const ToolPiece& piece, const Vec3& l0, const Vec3& l1, double within,
                     uint16_t* out) {
    const Vec3 d_l = l1 - l0;
    const double e_l = glm::dot(d_l, d_l);
    Aabb box;
    box.grow(l0);
    box.grow(l1);
    box.inflate(within);
    int hits = 0;
    auto exact = [&](uint32_t e) {
        const ModelTool::EdgeLine& line = tool.edge_lines[piece.edge_begin + e];
        double s_, t_;
        closest_segment_params(line.along, d_l, line.from - l0, line.length2, e_l, s_, t_);
        const Vec3 gap = (line.from + s_ * line.along) - (l0 + t_ * d_l);
        if (!root_exceeds(glm::dot(gap, gap), within)) out[hits++] = uint16_t(e);
    };
    // The lanes whose boxes meet the query box (Aabb::overlaps), as bits.
#if defined(__AVX2__)
    const __m256d qlo[3] = {lanes_of(box.lo.x), lanes_of(box.lo.y), lanes_of(box.lo.z)};
    const __m256d qhi[3] = {lanes_of(box.hi.x), lanes_of(box.hi.y), lanes_of(box.hi.z)};
    auto meets = [&](const ToolPiece::BoxLanes& b) {
        __m256d all = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
        for (int d = 0; d < 3; ++d) {
            all = _mm256_and_pd(all, _mm256_cmp_pd(_mm256_loadu_pd(b.lo[d]), qhi[d], _CMP_LE_OQ));
            all = _mm256_and_pd(all, _mm256_cmp_pd(qlo[d], _mm256_loadu_pd(b.hi[d]), _CMP_LE_OQ));
        }
        return unsigned(_mm256_movemask_pd(all));
    };
#else
    auto meets = [&](const ToolPiece::BoxLanes& b) {
        unsigned bits = 0;
        for (int k = 0; k < 4; ++k) {
            bool in = true;
            for (int d = 0; d < 3; ++d) in = in && b.lo[d][k] <= box.hi[d] && box.lo[d] <= b.hi[d][k];
            bits |= unsigned(in) << k;
        }
        return bits;
    };
#endif
    for (size_t g = 0; g < piece.edge_block_boxes.size(); ++g)
        for (unsigned blocks = meets(piece.edge_block_boxes[g]); blocks != 0; blocks &= blocks - 1) {
            const uint32_t b = uint32_t(4 * g) + uint32_t(__builtin_ctz(blocks));
            for (unsigned edges = meets(piece.edge_boxes[b]); edges != 0; edges &= edges - 1)
                exact(4 * b + uint32_t(__builtin_ctz(edges)));
        }
    return hits;
}

// How much a tick did before the end-of-tick slice (tend_superset): another pass or a release;
// many distance tests in detect, a burst of other work (a tissue set gathered anew, many of its
// bounds measured, many edge memos made anew, a second linearization, more than two candidates)
// or more time than RendererSettings::defer_after_us; few triangles tested in all; neither.
enum class Load { Passes, Heavy, Light, Usual };

// At the end of a tick: a slice of the superset in progress, or its install once complete (true
// when it did either). A tick with another pass or a release leaves it to a lighter one while the
// current superset had a tenth of its margin left at its last use, a heavy one while it had three
// tenths, so that the costs seldom meet; a light tick (few triangles tested) takes a double
// slice. Nothing for a build of another model (a tick that never reached the cache's check of the
// model, near_cache_begin).
bool tend_superset(const Model& model, NearCache& c, Load load) {
    SupersetBuild& b = c.build;
    if (!b.active || c.model_serial != model.serial) return false;
    const PieceNearCache& pc = c.piece[b.piece];
    if (load == Load::Passes || load == Load::Heavy) {
        const double spare = load == Load::Passes ? 0.1 : 0.3;
        if (pc.valid && pc.room_m > spare * pc.margin_m) return false;
    }
    // Walked to its end by the last slice: installed now, the walk's tick having had its slice.
    if (b.object >= model.objects.size()) install_superset(model, c);
    else advance_superset(model, c, load == Load::Light ? 2 * kSupersetSlice : kSupersetSlice);
    return true;
}

// Whether the earlier pass's complete near set (Workspace::prior) holds every triangle piece k can
// reach from pose `at` within the box [lower, upper] of the step's coordinates (in `frame`). The
// prior holds every triangle within its own reach (PieceReach::of, with the prior box's move and
// turn) of the piece at the prior's pose. A point p the piece brings within the contact distance
// of triangle T from the box moves at most move' + turn' |p - o| from the prior's pose
// (box_motion), so it was within the contact distance plus that of T there, with |p - o| at most
// u = min(radius, prior reach + rho) (rho: T's furthest vertex from the prior's origin) when the
// whole piece's need is within the prior's reach. The prior's reach of T is move + turn (u +
// move), with the same contact distance and room: it covers when move' + turn' u is no more for
// every u in [min(radius, prior reach), radius], that is at both ends.
bool prior_covers(const Model& model, size_t k, const Pose& at, const Mat3& frame, const double lower[6],
                  const double upper[6], const Workspace& w) {
    const PieceReach& prior = w.prior_reach[k];
    const double radius = model.tool.pieces[k].radius_m;
    const BoxMotion b = box_motion(w.prior_pose, at, frame, lower, upper);
    const double need = b.move_m + b.turn * radius + prior.contact + prior.room;
    if (!(need <= prior.reach)) return false;
    for (const double u : {std::min(radius, prior.reach), radius})
        if (!(b.move_m + b.turn * u <= prior.move + prior.turn * (u + prior.move))) return false;
    return true;
}

// How far inside object o the step looks for the tool's features (m): for a compliant object the
// tool's depth in it (`soft`) plus the step's reach, for a rigid one nothing. Gather looks that
// much further than the reach (gather_atoms' `far`).
double inside_reach(const Model& model, const SoftDepths& soft, uint16_t o, double reach) {
    return model.objects[o].compliant ? soft.of(o) + reach : 0.0;
}

// Gathers compliant set `c` anew about query box `b`: the slots whose boxes meet `b` widened by
// Workspace::kCompliantRoom, none measured yet. With `carry` (the same set gathered again as the
// tool moves on, its drift going on) a slot it already had keeps its quiet mark: the mark says how
// far the set's drift may grow before a vertex can come within the triangle's tests, whichever
// set holds it. Both lists come in increasing order (Bvh::query_slots): one pass over the old
// (copied aside) finds the slots in both. (Its bounds are measured again: carried, they were
// looser than the fresh ones and cost more downstream than measuring them.) False when they do
// not fit.
bool gather_compliant_set(const ModelObject& obj, const Aabb& b, bool carry, Workspace::CompliantSet& c,
                          Workspace& w) {
    const int old_count = carry ? c.count : 0;
    if (old_count > 0) {
        std::copy(c.slots, c.slots + old_count, w.carry_slots);
        std::copy(c.quiet, c.quiet + old_count, w.carry_quiet);
        std::copy(c.listed, c.listed + old_count, w.carry_listed);
    }
    c.box = b;
    c.box.inflate(Workspace::kCompliantRoom);
    c.query = b;
    c.count = 0;
    c.moved = 0.0;
    int j = 0;
    return obj.bvh.query_slots(c.box, [&](uint32_t slot) {
        if (c.count == Workspace::kCompliantSetSlots) return false;
        while (j < old_count && w.carry_slots[j] < slot) ++j;
        c.kept[c.count] = -1e300;
        const bool carried = j < old_count && w.carry_slots[j] == slot;
        c.quiet[c.count] = carried ? w.carry_quiet[j] : Workspace::kQuietUnknown;
        c.listed[c.count] = carried ? w.carry_listed[j] : 0;
        c.slots[c.count++] = slot;
        return true;
    });
}

// How far the last query box of set `c` is from leaving the set's box (m): its least gap to a
// face of it.
double compliant_room_left(const Workspace::CompliantSet& c) {
    const Vec3 below = c.query.lo - c.box.lo, above = c.box.hi - c.query.hi;
    return std::min(std::min(std::min(below.x, below.y), std::min(below.z, above.x)), std::min(above.y, above.z));
}

// At the end of a tick: the compliant set of this model that has the least room left, once that
// is under kCompliantRefresh of Workspace::kCompliantRoom, gathered anew about its last query box.
// The tool's pieces move together, and their sets left their boxes at the same tick (five walks
// of the tissue's hierarchy and some thousand triangles measured in one tick); one a tick, ahead
// of need, spreads them. What a query gets does not change: a set whose box holds it gives a fresh
// query's triangles in the same order, and measures those it has no bound for. Only the lower
// bounds they carry were measured at other times, and every use takes them as bounds.
constexpr double kCompliantRefresh = 0.5;
// A gathering anew costs some 125 K instructions and has the set's bounds measured at the next
// tick (some 700 of them). After a `busy` tick (a superset's slice, a burst of work, or a long
// one by the clock) the set waits for a later tick while it is the only one due and has this
// share of the room left; with two or more due, waiting one a tick in a spell of long ticks let
// three pieces outrun their sets at one tick. A tick where a piece has already outrun its set
// gathers none ahead.
constexpr double kCompliantRefreshBusy = 0.25;
void tend_compliant_sets(const Model& model, Workspace& w, bool busy) {
    if (w.compliant_gathers > 0) return;
    Workspace::CompliantSet* most = nullptr;
    double least = kCompliantRefresh * Workspace::kCompliantRoom;
    int due = 0;
    for (Workspace::CompliantSet& c : w.compliant_sets) {
        if (c.owner != w.owner || c.object >= model.objects.size()) continue;
        const double left = compliant_room_left(c);
        if (left < kCompliantRefresh * Workspace::kCompliantRoom) ++due;
        if (left < least) {
            least = left;
            most = &c;
        }
    }
    if (!most || (busy && due < 2 && least >= kCompliantRefreshBusy * Workspace::kCompliantRoom)) return;
    Workspace::CompliantSet& c = *most;
    ++w.compliant_gathers;
    if (!gather_compliant_set(model.objects[c.object], Aabb(c.query), true, c, w)) {
        c.owner = 0;
        c.used = 0;
    }
}

// At the end of a tick: some of the edge memos the tick's last gather found past kEdgeRenewShare
// of their slack made anew where they were then (Workspace::EdgeDue), those past kEdgeRenewUrgent
// first: none on a tick with another pass or a release. A memo made so is the one that gather would have
// made at that call, so no answer changes; it only runs out later, apart from the others made
// with it.
void tend_edge_memos(const Model& model, Workspace& w, Load load) {
    if (load == Load::Passes || w.edge_due_count == 0 || !model.settings.edge_memos_ahead) return;
    const bool heavy = load == Load::Heavy;
    int budget = heavy ? kEdgeRenewPerHeavyTick : kEdgeRenewPerTick;
    // Those past kEdgeRenewUrgent, then (not on a heavy tick) the rest.
    for (int round = 0; round < (heavy ? 1 : 2) && budget > 0; ++round) {
        const double least = round == 0 ? kEdgeRenewUrgent : kEdgeRenewShare;
        for (int i = 0; i < w.edge_due_count && budget > 0; ++i) {
            Workspace::EdgeDue& d = w.edge_due[i];
            if (!(d.share >= least)) continue;
            d.share = -1.0;
            --budget;
            if (d.memo->key != d.key) continue;
            const ToolPiece& piece = model.tool.pieces[feature_piece(d.key - 1)];
            ++w.edge_queries;
            ++w.edge_memos_ahead;
            const int hits = edge_hits_within(model.tool, piece, d.at[0], d.at[1],
                                              Workspace::edge_memo_within(d.far), w.edge_hits);
            if (hits <= Workspace::kEdgeMemoHits) d.memo->hold(d.at[0], d.at[1], d.far, w.edge_hits, hits);
        }
    }
}

// The triangles of `obj` whose boxes meet box `b`, for piece `pk` (a compliant object's, or any
// object's for a piece without capsules), each with the capsules' bound (piece_compliant_bound;
// none without capsules), in the hierarchy's order; with `any_only`, the first. False on overflow.
// Apart from gather_near, whose walk over the rigid objects' triangles it would otherwise crowd.
//
// With the near cache, a triangle that its bound where it was last measured, less how far the
// capsules have moved since (Workspace::CompliantSet), puts further than `beyond` from the piece
// comes with that lower bound instead of being measured again. `beyond` is the furthest that
// gather_atoms looks for the piece's features on this object (its `far`), so such a triangle is
// beyond there as it would be measured; and the step's other uses of the bound are no nearer
// (the guard: how far the piece moves in the step; CCD: an exact test where the bound leaves
// room).
[[gnu::noinline]] bool gather_in_box(const Model& model, const ModelObject& obj, uint16_t ok, const ToolPiece& piece,
                                     uint8_t pk, const CapsuleLine& line, const Aabb& b, double beyond, bool any_only,
                                     Workspace& w) {
    bool overflow = false;
    auto bound_of = [&](uint32_t tri) {
        const auto& t = obj.mesh.triangles[tri];
        return piece.capsule_count > 0
                   ? piece_compliant_bound(piece, line, obj.topology.triangle_spheres[tri], obj.mesh.vertices[t[0]],
                                           obj.mesh.vertices[t[1]], obj.mesh.vertices[t[2]])
                   : -1e300;
    };
    auto push = [&](uint32_t tri, double bound, uint16_t memo = 0) {
        if (w.near_count >= kMaxNear) {
            overflow = true;
            return false;
        }
        // Field by field in place (as NearTri{ok, tri, pk, bound} would leave them): no copy of a
        // whole triangle record through the stack, for each of the hundreds a tick gathers.
        NearTri& nt = w.near[w.near_count++];
        nt.object = ok;
        nt.tri = tri;
        nt.piece = pk;
        nt.lower_m = bound;
        nt.separation_m = std::numeric_limits<double>::quiet_NaN();
        nt.upper_m = 1e300;
        nt.direction = Vec3(0.0);
        nt.simplex = GjkSimplex{};
        nt.memo = memo;
        return !any_only;
    };
    auto visit = [&](uint32_t tri) { return push(tri, bound_of(tri)); };
    if (!model.settings.near_cache) {
        obj.bvh.query(b, visit);
        return !overflow;
    }
    // The set kept for this object and piece, if its box holds this one; else gathered anew, in
    // the same set or the one used longest ago (one of another session's counts as never used),
    // unless it would not fit.
    Workspace::CompliantSet* set = nullptr;
    for (Workspace::CompliantSet& c : w.compliant_sets)
        if (c.owner == w.owner && c.object == ok && c.piece == pk) {
            set = &c;
            break;
        }
    if (!set || !set->box.contains(b)) {
        if (!set) {
            set = &w.compliant_sets[0];
            for (Workspace::CompliantSet& c : w.compliant_sets)
                if (last_use(c, w.owner) < last_use(*set, w.owner)) set = &c;
        }
        Workspace::CompliantSet& c = *set;
        // Another object's or piece's set starts its drift afresh; the same set's goes on, with
        // its quiet marks.
        const bool same = c.owner == w.owner && c.object == ok && c.piece == pk;
        if (!same) {
            c.drift_call = 0;
            c.drift = 0.0;
        }
        c.owner = w.owner;
        c.object = ok;
        c.piece = pk;
        ++w.compliant_gathers;
        if (!gather_compliant_set(obj, b, same, c, w)) {
            c.owner = 0;
            c.used = 0;
            obj.bvh.query(b, visit);
            return !overflow;
        }
        if (piece.capsule_count > 0)
            for (int j = 0; j <= piece.capsule_count; ++j) c.axis[j] = line.axis[j];
    }
    Workspace::CompliantSet& c = *set;
    c.used = ++w.compliant_clock;
    c.query = b;
    // The set's index plus one above the slot (NearTriangle::memo).
    const uint16_t memo_set = uint16_t((set - w.compliant_sets + 1) << Workspace::kMemoSlotBits);
    // How far the capsules' points have moved since the last query: no point of a capsule moves
    // further than its ends (a rigid motion moves the points of a segment by the blend of its
    // ends' motions).
    const bool keep = piece.capsule_count > 0;
    double moved = 0.0;
    if (keep)
        for (int j = 0; j <= piece.capsule_count; ++j) {
            moved = std::max(moved, glm::length(line.axis[j] - c.axis[j]));
            c.axis[j] = line.axis[j];
        }
    c.moved += moved;
    // A picometre under, for the rounding of the sums.
    const double since = c.moved + 1e-12;
    // A measured bound, kept with how far the capsules had moved then.
    auto remember = [&](int slot, double bound) {
        c.kept[slot] = bound + c.moved;
        c.measured_at[slot] = c.moved;
        ++w.bounds_measured;
    };
    const std::vector<uint32_t>& order = obj.bvh.order();
#if defined(__AVX2__)
    // The triangles whose bounds are to be measured, four at a time: each is pushed at once, its
    // bound filled in (and kept) when its four are measured.
    int waiting = 0;
    uint32_t wait_tri[4];
    int wait_near[4], wait_slot[4];
    auto measure = [&] {
        if (waiting == 4) {
            const TriangleSphere* spheres[4];
            const Vec3* corners[4][3];
            for (int k = 0; k < 4; ++k) {
                spheres[k] = &obj.topology.triangle_spheres[wait_tri[k]];
                const auto& t = obj.mesh.triangles[wait_tri[k]];
                for (int m = 0; m < 3; ++m) corners[k][m] = &obj.mesh.vertices[t[m]];
            }
            double bounds[4];
            piece_compliant_bound4(piece, line, spheres, corners, bounds);
            for (int k = 0; k < 4; ++k) {
                w.near[wait_near[k]].lower_m = bounds[k];
                remember(wait_slot[k], bounds[k]);
            }
        } else {
            for (int k = 0; k < waiting; ++k) {
                const double bound = bound_of(wait_tri[k]);
                w.near[wait_near[k]].lower_m = bound;
                remember(wait_slot[k], bound);
            }
        }
        waiting = 0;
    };
#endif
#if defined(__AVX2__)
    const LanesBoxQuery query(b);
#endif
    for (int i = 0; i < c.count; ++i) {
        const uint32_t slot = c.slots[i];
#if defined(__AVX2__)
        if (!query.overlaps(obj.bvh.slot_box(slot))) continue;
#else
        if (!obj.bvh.slot_box(slot).overlaps(b)) continue;
#endif
        const uint32_t tri = order[slot];
        double bound = c.kept[i] - since;
        // A triangle measured since the capsules last moved kRemeasureMotion: its bound stands,
        // less the motion since (still a lower bound, if a looser one). Every use of the bound
        // takes it as a bound (gather_atoms' tests are exact, the guard measures what a bound does
        // not settle): measured again each tick, the triangles within `beyond` cost some 7 us a
        // tick of the tissue session for a few micrometres of bound.
        const bool stands = c.kept[i] > -1e299 && c.moved - c.measured_at[i] < kRemeasureMotion;
#if defined(__AVX2__)
        if (keep && !(bound > beyond) && !stands && w.near_count < kMaxNear) {
            wait_tri[waiting] = tri;
            wait_near[waiting] = w.near_count;
            wait_slot[waiting++] = i;
            const bool more = push(tri, 0.0, uint16_t(memo_set | i));
            if (waiting == 4 || !more) measure();
            if (!more) break;
            continue;
        }
#endif
        if (!keep || (!(bound > beyond) && !stands)) {
            bound = bound_of(tri);
            remember(i, bound);
        }
        if (!push(tri, bound, uint16_t(memo_set | i))) break;
    }
#if defined(__AVX2__)
    measure();
#endif
    return !overflow;
}

// detect: the triangles each piece of the tool can reach within the box [lower, upper] of the
// step's coordinates, each with a lower bound on its distance from the piece (for the guard).
// Against a rigid object a long piece (a probe's tip or shank) is bounded by its capsules: the BVH
// is walked along the chain of capsules, and a triangle is kept only when its distance bound to
// some capsule, and then its distance to the piece itself (GJK), are within how far that piece can
// move -- so a tilted probe does not collect the whole surface inside its box, nor the triangles
// its capsules' roundness comes near, and nothing it could touch is left out. With the near cache
// (RendererSettings::near_cache) the walk is over the piece's superset instead, and only triangles
// whose verdict the motion since their last measurement leaves open are measured; either way an
// object's triangles come in the order of their indices. A compliant object (which the tool enters)
// gives the triangles whose boxes meet the piece's box inflated by the tool's reach `reach_all`,
// each with the capsules' bound (piece_compliant_bound): gather_atoms looks among them for the face
// that holds a tool vertex inside it. A compact piece takes the triangles in its box inflated by
// its reach. With `any_only`, stops at the first triangle the capsules' bound keeps. With
// `prior_frame` (the frame of the box), a piece whose reach the earlier pass's near set covers
// (prior_covers) takes its triangles from that set, measured again only where the motion since
// leaves their verdict open. Needs the tool's vertices, planes and capsules placed at pose `at`
// (set_tool_planes). False on overflow.
bool gather_near(const Model& model, const Pose& at, const Vec3* tool_world, const double lower[6],
                 const double upper[6], double reach_all, Workspace& w, bool any_only = false,
                 const Mat3* prior_frame = nullptr) {
    w.near_count = 0;
    w.near_complete = false;
    bool narrowed = false;
    int prior_cursor = 0;  // w.prior is grouped by piece, then object, both in order
    bool overflow = false;
    auto push = [&](const NearTri& nt) {
        if (w.near_count >= kMaxNear) {
            overflow = true;
            return false;
        }
        w.near[w.near_count++] = nt;
        return !any_only;
    };
    // To a tenth of the constraint tolerance: enough for the guard's bound.
    const double tol = 0.1 * model.settings.constraint_tol_m;
    NearCache& cache = w.cache;
    const bool use_cache = !any_only && model.settings.near_cache;
    if (use_cache) near_cache_begin(cache, model, at);
    for (size_t k = 0; k < model.tool.pieces.size(); ++k) {
        const ToolPiece& piece = model.tool.pieces[k];
        const uint8_t pk = static_cast<uint8_t>(k);
        // How far this piece's points can move within the box.
        const PieceReach pr = piece_reach(model.settings, piece.radius_m, at.position, lower, upper);
        const double reach = pr.reach;
        w.near_reach[k] = pr;
        // How far a triangle's vertices are from the tool's origin (PieceReach::rho).
        auto rho_of = [&](const ModelObject& obj, uint32_t tri) {
            const auto& t = obj.mesh.triangles[tri];
            return pr.rho(obj.mesh.vertices[t[0]], obj.mesh.vertices[t[1]], obj.mesh.vertices[t[2]]);
        };
        const Vec3* axis = w.capsule + k * (kToolCapsules + 1);
        const CapsuleLine line = piece.capsule_count > 0 ? capsule_line(piece, axis) : CapsuleLine{};
#if defined(__AVX2__)
        const Aabb box = lanes_bounds(tool_world + piece.vertex_begin, int(piece.vertex_count));
#else
        Aabb box;
        for (uint32_t v = piece.vertex_begin; v < piece.vertex_begin + piece.vertex_count; ++v) box.grow(tool_world[v]);
#endif
        const ConvexView view = tool_view(model, k, tool_world, w);
        const bool from_prior = prior_frame && !any_only && piece.capsule_count > 0 &&
                                prior_covers(model, k, at, *prior_frame, lower, upper, w);
        narrowed |= from_prior;
        const double prior_motion = from_prior ? motion_bound(piece, w.prior_pose, at) : 0.0;
        const OriginMotion prior_origin = from_prior ? origin_motion(w.prior_pose, at) : OriginMotion{};
        PieceNearCache* pc = use_cache && piece.capsule_count > 0 && !from_prior
                                 ? piece_superset(model, cache, k, at, axis, reach, tol)
                                 : nullptr;
        int cursor = 0;  // pc's entries are grouped by object, in object order
        // The piece's box inflated for a compliant object and for a rigid one, once for all the
        // objects: made afresh for each, the box went through the stack in halves and came back
        // whole, a stall on every object (some 3 % of a tissue tick).
        Aabb box_all = box, box_reach = box;
        box_all.inflate(reach_all);
        box_reach.inflate(reach);
        for (size_t o = 0; o < model.objects.size(); ++o) {
            const ModelObject& obj = model.objects[o];
            const uint16_t ok = static_cast<uint16_t>(o);
            if (obj.compliant || piece.capsule_count == 0) {
                const Aabb& b = obj.compliant ? box_all : box_reach;
                // Most objects are nowhere near the piece: their hierarchy's root says so here.
                const auto& nodes = obj.bvh.nodes();
                if (nodes.empty() || !nodes[0].box.overlaps(b)) continue;
                // How far gather_atoms looks for the piece's features on this object (its `far`).
                const double beyond = reach_all + inside_reach(model, w.soft, ok, reach_all);
                overflow = !gather_in_box(model, obj, ok, piece, pk, line, b, beyond, any_only, w);
                if (overflow) return false;
                if (any_only && w.near_count > 0) return true;
                continue;
            }
            const int run = w.near_count;
            auto keep = [&](uint32_t tri, double lo, double hi, const Vec3& direction, const GjkSimplex& simplex) {
                NearTri nt{ok, tri, pk, lo};
                nt.upper_m = hi;
                // The distance where they are apart is the start separation the guard needs.
                if (lo > 0.0) nt.separation_m = lo;
                nt.direction = direction;
                nt.simplex = simplex;
                return push(nt);
            };
            // A triangle whose bounds [lo, hi] from an earlier pose, widened by the motion `m`
            // since, settle that it is in reach: kept with them, no separation (a bound this old
            // is too loose for the guard, which measures it itself where it needs it).
            auto keep_settled = [&](uint32_t tri, double lo, double hi, double m_lo, double m_hi,
                                    const Vec3& direction, const GjkSimplex& simplex) {
                NearTri nt{ok, tri, pk, lo - m_lo};
                nt.upper_m = hi + m_hi;
                nt.direction = direction;
                nt.simplex = simplex;
                return push(nt);
            };
            if (from_prior) {
                // The earlier pass's triangles of this piece and object, with their bounds there
                // widened by the motion since: kept or dropped where that settles it, else
                // measured.
                auto before = [&](const NearTri& q) { return q.piece < pk || (q.piece == pk && q.object < ok); };
                while (prior_cursor < w.prior_count && before(w.prior[prior_cursor])) ++prior_cursor;
                for (; prior_cursor < w.prior_count && w.prior[prior_cursor].piece == pk &&
                       w.prior[prior_cursor].object == ok && !overflow;
                     ++prior_cursor) {
                    const NearTri& q = w.prior[prior_cursor];
                    const double rho = rho_of(obj, q.tri), tri_reach = pr.of(rho);
                    // The motion since, the piece's or the triangle's (triangle_motion), whichever is less.
                    const double m_lo = std::min(prior_motion, triangle_motion(prior_origin, q.lower_m, rho));
                    const double m_hi = std::min(prior_motion, triangle_motion(prior_origin, q.upper_m, rho));
                    const Settled verdict = settle(q.lower_m, q.upper_m, m_lo, m_hi, tri_reach, tol);
                    if (verdict == Settled::Out) continue;
                    if (verdict == Settled::In) {
                        if (!keep_settled(q.tri, q.lower_m, q.upper_m, m_lo, m_hi, q.direction, q.simplex)) break;
                        continue;
                    }
                    // Left open, the earlier pass's direction and simplex taken at this base
                    // (a search of no iterations) mostly settle it: that pass's answer moved the
                    // tool a few micrometres, which the motion's bound makes nearly half the reach.
                    // The lower bound is this base's, so the guard starts from it.
                    const bool hinted = glm::dot(q.direction, q.direction) > 0.0;
                    if (hinted || q.simplex.count > 0) {
                        const auto& t = obj.mesh.triangles[q.tri];
                        const DistanceBounds b = convex_triangle_distance(
                            view, obj.mesh.vertices[t[0]], obj.mesh.vertices[t[1]], obj.mesh.vertices[t[2]], 1e300, tol,
                            0, hinted ? &q.direction : nullptr, q.simplex.count > 0 ? &q.simplex : nullptr);
                        const double lo = std::max(b.lower, q.lower_m - m_lo);
                        if (lo > tri_reach + tol) continue;
                        if (b.upper <= tri_reach) {
                            keep(q.tri, lo, b.upper, q.direction, b.simplex.count > 0 ? b.simplex : q.simplex);
                            continue;
                        }
                    }
                    ++w.detect_tests;
                    const NearVerdict v =
                        judge_near(model, k, view, line, obj, q.tri, tri_reach, tol, false, 2.0 * reach, &q.direction,
                                   &q.simplex);
                    if (v.keep)
                        keep(q.tri, v.lo, v.hi, glm::dot(v.direction, v.direction) > 0.0 ? v.direction : q.direction,
                             v.simplex.count > 0 ? v.simplex : q.simplex);
                }
            } else if (pc) {
                const double path = cache.path_m[k];
                // With room for the rounding of the sums along the path.
                const double skip_over = reach + tol + 1e-15 * (1.0 + path);
                // This object's run of entries.
                const int end = int(std::find_if(pc->object + cursor, pc->object + pc->count,
                                                 [ok](uint16_t x) { return x != ok; }) -
                                    pc->object);
                const double* const due = pc->due;
                for (; cursor < end && !overflow; ++cursor) {
                    // Out of reach while the path has not grown by its distance bound since.
                    while (cursor < end && due[cursor] - path > skip_over) ++cursor;
                    if (cursor == end) break;
                    NearCacheEntry& e = pc->entries[cursor];
                    double m;
                    const bool known = near_cache_entry_motion(cache, model, e, k, m);
                    // Before its pose leaves the ring, a settled entry's bounds move to the
                    // current pose (widened by the motion since), rather than being bounded by
                    // the looser path once forgotten.
                    const bool rebase = cache.stamp - e.stamp >= uint64_t(kNearCacheSlots / 2);
                    if (known && !rebase && e.lo - m > reach + tol) {
                        // Out of the piece's reach, so of the triangle's: its mesh is not read.
                        pc->due[cursor] = (e.lo - m) + path;
                        continue;
                    }
                    const double rho = rho_of(obj, e.tri), tri_reach = pr.of(rho);
                    if (known) {
                        // The piece's motion since, or the triangle's (triangle_motion) while the
                        // entry's pose is kept, whichever is less.
                        double m_lo = m, m_hi = m;
                        OriginMotion om;
                        const bool kept = near_cache_origin_motion(cache, e.stamp, om);
                        if (kept) {
                            m_lo = std::min(m, triangle_motion(om, e.lo, rho));
                            m_hi = std::min(m, triangle_motion(om, e.hi, rho));
                        }
                        Settled verdict = settle(e.lo, e.hi, m_lo, m_hi, tri_reach, tol);
                        // Left open, the gap along the last direction may still settle it: the
                        // tool sliding along a surface hardly nears the triangles beside it.
                        double along = -1e300;
                        if (verdict == Settled::Open && kept) {
                            along = direction_lower_bound(om, e.direction, e.direction_gap, piece.radius_m);
                            if (e.lo - along < m_lo) {
                                m_lo = e.lo - along;
                                verdict = settle(e.lo, e.hi, m_lo, m_hi, tri_reach, tol);
                            }
                        }
                        const bool out = verdict == Settled::Out, in = verdict == Settled::In;
                        if (in && !keep_settled(e.tri, e.lo, e.hi, m_lo, m_hi, e.direction, e.simplex)) break;
                        if (out || in) {
                            pc->due[cursor] = (e.lo - m_lo) + path;
                            if (rebase) {
                                // The gap along the direction, where it was not measured, no less
                                // than the motion leaves of it.
                                e.direction_gap =
                                    kept ? direction_lower_bound(om, e.direction, e.direction_gap, piece.radius_m)
                                         : -1e300;
                                e.lo -= m_lo;
                                if (e.hi < 1e300) e.hi += m_hi;
                                e.stamp = cache.stamp;
                                e.path_m = path;
                            }
                            continue;
                        }
                    }
                    ++w.detect_tests;
                    const NearVerdict v =
                        judge_near(model, k, view, line, obj, e.tri, tri_reach, tol, false, 2.0 * reach, &e.direction,
                                   &e.simplex);
                    e.lo = v.lo;
                    e.hi = v.hi;
                    // A direction of this measurement comes with its gap; an older one has none here.
                    const bool measured = glm::dot(v.direction, v.direction) > 0.0;
                    if (measured) e.direction = v.direction;
                    e.direction_gap = measured ? v.direction_gap : -1e300;
                    if (v.simplex.count > 0) e.simplex = v.simplex;
                    e.stamp = cache.stamp;
                    e.path_m = path;
                    pc->due[cursor] = v.lo + path;
                    if (v.keep) keep(e.tri, v.lo, v.hi, e.direction, e.simplex);
                }
            } else {
                // Along the piece's capsules; a triangle within reach of their bound is kept only
                // when GJK finds it within reach of the piece itself.
                obj.bvh.query_capsule_chain(axis, piece.capsule_radii_m.data(), piece.capsule_count, reach,
                                            [&](uint32_t tri) {
                                                ++w.detect_tests;
                                                const NearVerdict v = judge_near(model, k, view, line, obj, tri,
                                                                                 pr.of(rho_of(obj, tri)), tol, any_only);
                                                return v.keep ? keep(tri, v.lo, v.hi, v.direction, v.simplex) : true;
                                            });
            }
            if (overflow) return false;
            if (any_only && w.near_count > 0) return true;
            std::sort(w.near + run, w.near + w.near_count, [](const NearTri& x, const NearTri& y) { return x.tri < y.tri; });
        }
    }
    w.near_complete = !any_only && !narrowed;
    return true;
}

// detect, free motion: true when the whole motion stays farther than `clearance` from every
// triangle in reach.
bool motion_is_free(const Model& model, const Pose& base, const double x[6], double clearance, Workspace& w) {
    const CcdResult r =
        conservative_advancement(model, base, x, clearance, w.near, w.near_count, kMaxCcdIterations, true);
    w.tests += r.tests;
    return !r.hit;
}

void add_atom(Workspace& w, const Atom& a) {
    if (w.atom_count < kMaxAtoms) w.atoms[w.atom_count++] = a;
    else w.gather_full = true;
}

// add_atom for gather's F-V and E-E loops: the atom notes the object feature it was made for
// (order_by_feature). Whether it fit.
bool add_feature_atom(Workspace& w, const Atom& a, uint64_t feature) {
    if (w.atom_count < kMaxAtoms) w.atom_feature[w.atom_count] = feature;
    const int before = w.atom_count;
    add_atom(w, a);
    return w.atom_count > before;
}

void add_alt(Workspace& w, int replace, const Atom& a) {
    // An alternative to an atom that did not fit has nothing to replace.
    if (replace < w.atom_count && w.alt_count < kMaxAlts) w.alts[w.alt_count++] = Alt{replace, a};
}

Atom vf_atom(uint16_t object, uint32_t tool_vertex, uint32_t tri) {
    Atom a;
    a.kind = AtomKind::VertexFace;
    a.object = object;
    a.tool_vertex = tool_vertex;
    a.object_triangle = tri;
    return a;
}

double signed_to_plane(const ModelObject& obj, uint32_t tri, const Vec3& p) {
    return glm::dot(obj.topology.triangle_normals[tri], p - obj.mesh.vertices[obj.mesh.triangles[tri][0]]);
}

// Resolves a disjunction: the tool vertex must stay in front of one of the faces `tris`
// (a convex edge or vertex). The face it is most in front of becomes the atom; faces within
// tie_tol of it become candidates.
void add_disjunction(const Model& model, Workspace& w, uint16_t object, uint32_t a, const Vec3& wa,
                     const uint32_t* tris, int count, double back) {
    const ModelObject& obj = model.objects[object];
    int best = -1;
    double best_d = -1e300;
    for (int i = 0; i < count; ++i) {
        const double d = signed_to_plane(obj, tris[i], wa);
        if (d > best_d) {
            best_d = d;
            best = i;
        }
    }
    if (best < 0 || best_d < -back) return;
    const int index = w.atom_count;
    add_atom(w, vf_atom(object, a, tris[best]));
    for (int i = 0; i < count; ++i) {
        if (i == best) continue;
        const double d = signed_to_plane(obj, tris[i], wa);
        if (d >= best_d - model.settings.tie_tol_m &&
            glm::dot(obj.topology.triangle_normals[tris[i]], obj.topology.triangle_normals[tris[best]]) < 1.0 - 1e-12)
            add_alt(w, index, vf_atom(object, a, tris[i]));
    }
}

// A tool vertex clearly off a convex edge or a vertex, in its Voronoi region: the plane through
// the feature facing the vertex (normal along feature -> vertex) separates it from the solid
// there (Types 8 and 9 as a dynamic plane, frozen for the step). Unlike one of the feature's face
// planes, it does not reach past the feature, so the tool is never held on a face's extended
// plane millimetres from the face.
constexpr double kOffFeature = 1e-6;

void add_feature_plane(Workspace& w, uint16_t object, uint32_t a, const Vec3& wa, const Vec3& on_feature,
                       uint32_t feature_vertex, uint32_t tri) {
    Atom at;
    at.kind = AtomKind::FixedAxis;
    at.object = object;
    at.tool_vertex = a;
    at.object_vertex = feature_vertex;
    at.object_triangle = tri;
    at.axis = glm::normalize(wa - on_feature);
    add_atom(w, at);
}

bool in_vertex_cone(const ModelObject& obj, uint32_t v, const Vec3& p) {
    const auto& topo = obj.topology;
    const Vec3& pv = obj.mesh.vertices[v];
    const Vec3 d = p - pv;
    for (uint32_t i = topo.vertex_edge_offsets[v]; i < topo.vertex_edge_offsets[v + 1]; ++i) {
        const MeshEdge& e = topo.edges[topo.vertex_edges[i]];
        const uint32_t other = e.v[0] == v ? e.v[1] : e.v[0];
        const Vec3 dir = obj.mesh.vertices[other] - pv;
        if (glm::dot(d, dir) > 1e-12 * glm::length(dir)) return false;
    }
    return true;
}

// The feature of triangle `tri` that holds tool vertex a's closest point (its region).
inline FeatureKey feature_key(const ModelObject& obj, uint16_t object, uint32_t tri, uint32_t a, TriRegion region) {
    FeatureKey key{a, object, 0, tri};
    switch (region) {
        case TriRegion::Face: break;
        case TriRegion::Edge0: key.type = 1; key.id = obj.topology.triangle_edges[tri][0]; break;
        case TriRegion::Edge1: key.type = 1; key.id = obj.topology.triangle_edges[tri][1]; break;
        case TriRegion::Edge2: key.type = 1; key.id = obj.topology.triangle_edges[tri][2]; break;
        case TriRegion::Vertex0: key.type = 2; key.id = obj.mesh.triangles[tri][0]; break;
        case TriRegion::Vertex1: key.type = 2; key.id = obj.mesh.triangles[tri][1]; break;
        case TriRegion::Vertex2: key.type = 2; key.id = obj.mesh.triangles[tri][2]; break;
    }
    return key;
}

// The atoms of tool vertex k.a, at world point `wa`, against the object feature of key k (Table
// 1 by the feature's convexity); faces `back` behind the vertex or more are across the solid.
void add_feature_atoms(const Model& model, Workspace& w, const FeatureKey& k, const Vec3& wa, double back) {
    const ModelObject& obj = model.objects[k.object];
    if (k.type == 0) {
        add_atom(w, vf_atom(k.object, k.a, k.id));
    } else if (k.type == 1) {
        const MeshEdge& e = obj.topology.edges[k.id];
        if (e.convexity == Convexity::Flat) {
            // A flat edge is no feature of the surface: a point beyond one of its triangles
            // lies over the other (whose face holds it) or beyond both, where another edge
            // or vertex is the real feature. Only a point right over the edge, which both
            // triangles report as an edge point, is held by their common plane.
            const Vec3& v0 = obj.mesh.vertices[e.v[0]];
            const Vec3 ev = obj.mesh.vertices[e.v[1]] - v0;
            const double s = glm::clamp(glm::dot(wa - v0, ev) / glm::dot(ev, ev), 0.0, 1.0);
            const Vec3 off = wa - (v0 + s * ev);
            const double h = signed_to_plane(obj, e.tri[0], wa);
            if (glm::dot(off, off) - h * h <= 1e-18 && h >= -back) add_atom(w, vf_atom(k.object, k.a, e.tri[0]));
        } else if (e.convexity == Convexity::Concave) {
            // eq. 8: both faces of a concave edge hold at once (Types 3 and 5) for a vertex
            // resting in the valley. A vertex clearly off it is over one of the faces, whose
            // own region holds it; their planes reach past the valley and would hold it on
            // an extended plane.
            const Vec3& v0 = obj.mesh.vertices[e.v[0]];
            const Vec3 ev = obj.mesh.vertices[e.v[1]] - v0;
            const double t = glm::clamp(glm::dot(wa - v0, ev) / glm::dot(ev, ev), 0.0, 1.0);
            if (glm::length(wa - (v0 + t * ev)) > kOffFeature) return;
            for (uint32_t tri : e.tri)
                if (signed_to_plane(obj, tri, wa) >= -back) add_atom(w, vf_atom(k.object, k.a, tri));
        } else {
            // Convex edge (Types 2, 8): the face the vertex is in front of while it rests on
            // the edge; the edge's own plane while it is clearly off it.
            const Vec3& v0 = obj.mesh.vertices[e.v[0]];
            const Vec3 ev = obj.mesh.vertices[e.v[1]] - v0;
            const double t = glm::clamp(glm::dot(wa - v0, ev) / glm::dot(ev, ev), 0.0, 1.0);
            const Vec3 c = v0 + t * ev;
            const Vec3 u = wa - c;
            if (glm::length(u) <= kOffFeature || t <= 0.0 || t >= 1.0) {
                add_disjunction(model, w, k.object, k.a, wa, e.tri.data(), 2, back);
            } else {
                // Only in the edge's normal cone (between its faces' normals) is the edge the
                // nearest feature; elsewhere the point is over a face, which holds it. The cone's
                // sides count as in it, to well past rounding: a vertex held on a face's plane
                // that has slid off the face (the rescue's case) lies on a side.
                const Vec3& n1 = obj.topology.triangle_normals[e.tri[0]];
                const Vec3& n2 = obj.topology.triangle_normals[e.tri[1]];
                const double k12 = glm::dot(n1, n2), u1 = glm::dot(u, n1), u2 = glm::dot(u, n2);
                const double side = -1e-9 * glm::length(u);
                if (u1 - k12 * u2 >= side && u2 - k12 * u1 >= side)
                    add_feature_plane(w, k.object, k.a, wa, c, e.v[0], u1 >= u2 ? e.tri[0] : e.tri[1]);
            }
        }
    } else {
        const auto& topo = obj.topology;
        // The vertex is the feature only for points in its Voronoi cone: no incident edge
        // leans towards the point (else the point is over that edge or a face beyond it,
        // which another triangle reports).
        if (!in_vertex_cone(obj, k.id, wa)) return;
        const uint32_t* tris = topo.vertex_triangles.data() + topo.vertex_triangle_offsets[k.id];
        const int count = static_cast<int>(topo.vertex_triangle_offsets[k.id + 1] - topo.vertex_triangle_offsets[k.id]);
        if (topo.vertex_convexity[k.id] == Convexity::Concave) {
            // eq. 8: every face around a concave vertex (Type 4), for a vertex resting in it.
            if (glm::length(wa - obj.mesh.vertices[k.id]) > kOffFeature) return;
            for (int j = 0; j < count; ++j)
                if (signed_to_plane(obj, tris[j], wa) >= -back) add_atom(w, vf_atom(k.object, k.a, tris[j]));
        } else if (glm::length(wa - obj.mesh.vertices[k.id]) > kOffFeature) {
            // Clearly off the vertex, in its Voronoi cone (Type 9): its own plane.
            int best = 0;
            for (int j = 1; j < count; ++j)
                if (signed_to_plane(obj, tris[j], wa) > signed_to_plane(obj, tris[best], wa)) best = j;
            add_feature_plane(w, k.object, k.a, wa, obj.mesh.vertices[k.id], k.id, tris[best]);
        } else {
            add_disjunction(model, w, k.object, k.a, wa, tris, count, back);
        }
    }
}

// The contact zone of an atom's object feature.
uint16_t atom_zone(const Model& model, const Atom& a) {
    const ModelObject& o = model.objects[a.object];
    if (o.triangle_zone.empty()) return o.zone;
    switch (a.kind) {
        case AtomKind::VertexFace:
        case AtomKind::FixedAxis: return o.triangle_zone[a.object_triangle];
        case AtomKind::FaceVertex: return o.vertex_zone[a.object_vertex];
        case AtomKind::EdgeEdge: return o.triangle_zone[o.topology.edges[a.object_edge].tri[0]];
    }
    return o.zone;
}

const ModelMaterial& zone_material(const Model& model, uint16_t zone) {
    return model.materials[model.zone_material[zone]];
}

// Atoms of a compliant zone that cannot hold the tool anywhere in the step's box, left out of
// gather's set. The atoms of a zone share its give s >= 0 (the sum of its springs): each holds
// when g + c s >= 0, with c = 1 where the zone gives way along its normals and c = n . d >= 0
// where it translates along d. So atom i cannot hold the tool (it holds, out of contact, wherever
// the rest do) where over the whole box
//   - g_i stays above 0 by the contact distance and more: it holds whatever the give; or
//   - (c = 1) g_i stays above g_j by as much, for an atom j of the same zone in every candidate:
//     j holding makes i hold.
// A candidate's solution is the same with and without i. Over the box a tool point at distance
// rho from the tool's origin moves by at most box.move + box.turn (rho + box.move) (PieceReach,
// with its room), so that, from the values at the base g0,
//   - a V-F or separating-plane atom (a plane fixed in the world) stays within that of g0: these
//     are the covering atoms j (ZoneCover::covered), and are left out themselves by both tests;
//   - an E-E or F-V atom is n . (P - Q) with P the point of the tool's line or face nearest the
//     other feature at the base (P - Q = g0 n0) and n the atom's unit normal; as n turns,
//     n . (P - Q) = g0 (n . n0) is at least -|g0|, so the atom is at least -|g0| less the motion
//     of P (for E-E, a point of the tool's edge; for F-V the object vertex's foot on the face's
//     plane, no further from the origin than the vertex is, plus |g0|): only the second test
//     can leave it out.
// So deep in a zone, only the atoms about as deep as its deepest V-F atom stay, and outside it
// those within the reach. An atom that is the default of an alternative stays.
struct ZoneCover {
    static constexpr int kZones = 16;
    int zones = 0;
    uint16_t zone[kZones];
    // Per zone, the least bound above of a covering atom's value over the box (m; +inf with none,
    // and in a zone that gives way along one direction).
    double covered[kZones];
    PieceReach box;              // the step's box
    double margin = 0.0;         // the contact distance and twice the constraint tolerance (m)
    double vertex_motion = 0.0;  // how far a tool vertex moves in the box, at most (m)

    ZoneCover(const Model& model, const PieceReach& b)
        : box(b),
          margin(model.settings.contact_distance_m + 2.0 * model.settings.constraint_tol_m),
          vertex_motion(motion(model.tool.radius_m)) {}

    // How far a point rho from the tool's origin, fixed to the tool, moves in the box at most, with
    // the reach's room (m).
    double motion(double rho) const { return box.move + box.turn * (rho + box.move) + box.contact + box.room; }

    // A value (m) over which a V-F or separating-plane atom of a compliant zone holds over the
    // whole box, out of contact, whatever the give.
    double far_plane() const { return vertex_motion + margin; }

    // The value (m) an atom of zone z must stay above over the box to be left out; +inf for a zone
    // not seen.
    double limit(uint16_t z) const {
        for (int k = 0; k < zones; ++k)
            if (zone[k] == z) return std::min(covered[k], 0.0) + margin;
        return 1e300;
    }
};

// Whether the feature of key k of a compliant object, `distance` (over `far_plane`) from its tool
// vertex at `wa`, gives the vertex no atom that can hold (add_feature_atoms, ZoneCover): a convex
// edge (the vertex over a point between its ends) or a convex or mixed vertex gives at most its own
// plane, whose value is that distance; a concave one gives nothing that far off. Such a feature
// need not be looked at. A flat edge may give the plane of its faces, which the vertex may be
// behind.
// (Inlined: gather asks it of every edge and vertex feature of the tissue it finds.)
[[gnu::always_inline]] inline bool leaves_out_far_plane(const Model& model, const FeatureKey& k, const Vec3& wa,
                                                        double distance, double far_plane) {
    if (!(distance > far_plane) || k.type == 0) return false;
    const ModelObject& obj = model.objects[k.object];
    if (k.type == 2) return true;
    const MeshEdge& e = obj.topology.edges[k.id];
    if (e.convexity == Convexity::Concave) return true;
    if (e.convexity != Convexity::Convex) return false;
    const Vec3& v0 = obj.mesh.vertices[e.v[0]];
    const Vec3 ev = obj.mesh.vertices[e.v[1]] - v0;
    const double t = glm::clamp(glm::dot(wa - v0, ev) / glm::dot(ev, ev), 0.0, 1.0);
    return t > 0.0 && t < 1.0;
}

// Whether zone z of an object is compliant, and (along_normals) gives way along its normals.
bool compliant_zone(const Model& model, uint16_t object, uint16_t z, bool along_normals) {
    if (!model.objects[object].compliant || !zone_material(model, z).compliant) return false;
    const Vec3& d = model.zone_direction[z];
    return !along_normals || (d.x == 0.0 && d.y == 0.0 && d.z == 0.0);
}

// The zones' bounds in `c` from gather's V-F and separating-plane atoms (all of them are made
// before the F-V and E-E atoms); each such atom's zone slot and value at the base stay in the
// workspace for remove_covered_atoms.
void cover_zones(const Model& model, const Pose& base, Workspace& w, ZoneCover& c) {
    if (!model.any_compliant || !model.settings.drop_covered_atoms) return;
    const double x0[6] = {};
    const ToolPoseAt at = tool_pose_at(base, x0);
    int8_t* const slot = w.atom_zone_slot;
    for (int i = 0; i < w.atom_count; ++i) {
        slot[i] = -1;
        const Atom& a = w.atoms[i];
        const uint16_t z = atom_zone(model, a);
        if (!compliant_zone(model, a.object, z, false)) continue;
        int k = 0;
        while (k < c.zones && c.zone[k] != z) ++k;
        if (k == c.zones) {
            if (c.zones == ZoneCover::kZones) continue;
            c.zone[c.zones] = z;
            c.covered[c.zones++] = 1e300;
        }
        slot[i] = int8_t(k);
        w.atom_value[i] = evaluate_atom(model, a, at, nullptr);
    }
    for (int k = 0; k < w.alt_count; ++k) slot[w.alts[k].replace] = -1;
    for (int i = 0; i < w.atom_count; ++i)
        if (slot[i] >= 0 && compliant_zone(model, w.atoms[i].object, c.zone[slot[i]], true))
            c.covered[slot[i]] = std::min(c.covered[slot[i]], w.atom_value[i] + c.vertex_motion);
}

// Drops those of the first `count` atoms (the ones cover_zones saw) that cannot hold the tool,
// keeping the order.
void remove_covered_atoms(const ZoneCover& c, int count, Workspace& w) {
    if (c.zones == 0) return;
    int kept = 0;
    for (int i = 0; i < w.atom_count; ++i) {
        const int k = i < count ? w.atom_zone_slot[i] : -1;
        const bool drop = k >= 0 && w.atom_value[i] - c.vertex_motion > std::min(c.covered[k], 0.0) + c.margin;
        w.atom_moved_to[i] = drop ? -1 : kept;
        if (!drop) w.atoms[kept++] = w.atoms[i];
    }
    if (kept == w.atom_count) return;
    for (int k = 0; k < w.alt_count; ++k) w.alts[k].replace = w.atom_moved_to[w.alts[k].replace];
    w.atom_count = kept;
}

// The gather's features in key order without repeats (neighbouring triangles give a tool vertex
// the same edge or vertex): packed into numbers, the repeats dropped and the rest sorted by
// sort_unique, as std::sort and std::unique would leave them.
void sort_features(Workspace& w) {
    static_assert(kMaxObjFeatures >= kMaxFeatures, "feature_scratch holds a gather's features");
    for (int i = 0; i < w.feat_count; ++i) w.feat_keys[i] = packed_feature(w.feats[i]);
    w.feat_count = sort_unique(w.feat_keys, w.feature_scratch, w.feat_count, w.feature_table);
    for (int i = 0; i < w.feat_count; ++i) w.feats[i] = unpacked_feature(w.feat_keys[i]);
}

// An E-E atom's pair (Type 2, on the dynamic plane of eq. 7): tool edge a0-a1 and object edge
// from v0 along eo (eo2 its squared length, bisector the sum of its faces' normals).
struct EdgePair {
    double sign = 1.0;    // the atom's orientation of u
    Vec3 u{0.0};          // eo x (a1 - a0)
    double u_length = 0.0;
    double behind = 0.0;  // how far the tool edge is in front of the object edge (m; < 0 behind)
};

// Whether the pair may make an atom: the closest points lie inside both edges (at an end of
// either, most pairs, a vertex's atom holds instead) within `far`, and the edges are not
// near-parallel (the plane of eq. 7 is undefined there; the vertices' atoms hold). The caller
// leaves out a pair whose tool edge is too far behind the object edge (`behind`): across the
// solid from it, not a contact.
// (Inlined: gather tests some ten thousand pairs a tick.)
[[gnu::always_inline]] inline bool edge_pair(const Vec3& a0, const Vec3& a1, const Vec3& v0, const Vec3& eo,
                                             double eo2, const Vec3& bisector, double far, EdgePair& p) {
    const Vec3 et = a1 - a0;
    const double ee = glm::dot(et, et);
    double s, t;
    closest_segment_params(et, eo, a0 - v0, ee, eo2, s, t);
    if (s <= 1e-9 || s >= 1.0 - 1e-9 || t <= 1e-9 || t >= 1.0 - 1e-9) return false;
    const Vec3 gap = (a0 + s * et) - (v0 + t * eo);
    if (root_exceeds(glm::dot(gap, gap), far)) return false;
    p.u = glm::cross(eo, et);
    p.u_length = glm::length(p.u);
    if (p.u_length < 1e-3 * glm::length(eo) * glm::length(et)) return false;
    const double ub = glm::dot(p.u, bisector);
    if (std::abs(ub) > 1e-6 * p.u_length * glm::length(bisector)) {
        p.sign = ub > 0.0 ? 1.0 : -1.0;
    } else {
        const double g = glm::dot(p.u, a0 - v0);
        if (g == 0.0) return false;
        p.sign = g > 0.0 ? 1.0 : -1.0;
    }
    p.behind = p.sign * glm::dot(p.u / p.u_length, a0 - v0);
    return true;
}

// The atoms gather made from `first` on, each for its object feature (w.atom_feature), put in the
// order of those features and, for one feature, in the order they were made; with `alts`, the
// alternatives made with them (w.alt_made, each replacing the one atom of its own feature)
// appended to w.alts in the same order, as many as fit. The F-V and E-E loops take their features
// as the table that drops the repeats leaves them (in the near set's order): this gives the atoms
// and alternatives the order that taking the features sorted gave them, without sorting the
// features (some hundreds a tick) first. (Of more than kMaxAtoms alternatives, the first made
// are kept; the step keeps kMaxAlts.)
void order_by_feature(Workspace& w, int first, bool alts) {
    const int n = w.atom_count - first;
    int* const order = w.order_index;  // the atoms' old places, in their new order
    int* const place = w.atom_moved_to;  // each atom's new place, by its old one less `first`
    for (int j = 0; j < n; ++j) order[j] = first + j;
    auto before = [&](int a, int b) {
        return w.atom_feature[a] != w.atom_feature[b] ? w.atom_feature[a] < w.atom_feature[b] : a < b;
    };
    if (!std::is_sorted(order, order + n, before)) {
        std::sort(order, order + n, before);
        for (int j = 0; j < n; ++j) w.order_atoms[j] = w.atoms[order[j]];
        std::copy(w.order_atoms, w.order_atoms + n, w.atoms + first);
    }
    for (int j = 0; j < n; ++j) place[order[j] - first] = first + j;
    if (!alts) return;
    // By the new place of the atom each replaces, then as made.
    uint64_t* const keys = w.order_keys;
    for (int k = 0; k < w.alt_made_count; ++k)
        keys[k] = uint64_t(place[w.alt_made[k].replace - first]) << 32 | uint32_t(k);
    if (!std::is_sorted(keys, keys + w.alt_made_count)) std::sort(keys, keys + w.alt_made_count);
    for (int k = 0; k < w.alt_made_count; ++k) {
        const Alt& a = w.alt_made[uint32_t(keys[k])];
        add_alt(w, int(keys[k] >> 32), a.atom);
    }
}

// The flat edges of triangle `tri` of `obj` (bit k: edge k, triangle_edges' order), kept in
// `known` (-1: not yet asked).
int flat_edges_of(const ModelObject& obj, uint32_t tri, int& known) {
    if (known < 0) {
        known = 0;
        for (int k = 0; k < 3; ++k)
            known |= int(obj.topology.edges[obj.topology.triangle_edges[tri][k]].convexity == Convexity::Flat) << k;
    }
    return known;
}

// gather: the principal-contact atoms of every feature pair within `reach`. The tool may be inside
// a compliant object by as deep as it is at the base (Workspace::soft) plus the reach: that
// object's features stay in play that far behind their surface. False when a tool vertex's
// feature or an atom did not fit (deep in a compliant object): those are left out, and the
// guard holds the tool off whatever they would have held (StepStats::gather_truncated). A
// smaller box does not help there: the depth, not the motion, makes the set.
bool gather_atoms(const Model& model, const Pose& base, const double lower[6], const double upper[6], const Vec3& push,
                  Workspace& w) {
    const ModelTool& tool = model.tool;
    const PieceReach box = piece_reach(model.settings, tool.radius_m, base.position, lower, upper);
    const double reach = box.reach;
    // What cannot hold in the box (ZoneCover): its zones' bounds follow the V-F atoms.
    ZoneCover cover(model, box);
    const SoftDepths& soft = w.soft;
    // World to the tool's frame (rotation part), for the E-E boxes.
    const Mat3 to_tool = glm::mat3_cast(glm::conjugate(base.orientation));
    // How far inside object o a feature may be (the last object's kept: features come grouped
    // by object).
    int in_object = -1;
    double in_depth = 0.0, in_back = 0.0;
    auto in_of = [&](uint16_t o) {
        if (o != in_object) {
            in_object = o;
            in_depth = inside_reach(model, soft, o, reach);
            in_back = back_face(model.settings, model.objects[o].compliant) + in_depth;
        }
        return in_depth;
    };
    // How far behind a feature of object o a tool feature still faces it.
    auto back_of = [&](uint16_t o) {
        in_of(o);
        return in_back;
    };
    auto reach_of = [&](uint16_t o) { return reach + in_of(o); };
    // A compliant set's drift (Workspace::CompliantSet), added to once in this call: the motion
    // of the piece's vertices since the set's last gather, and the rise of the tests' bounds
    // (`far` by twice the reach's rise and once the depth's, `reach` and `back` by less).
    const uint64_t call = ++w.gather_clock;
    w.edge_due_count = 0;
    auto add_drift = [&](Workspace::CompliantSet& c, uint16_t o) {
        if (c.drift_call == call) return;
        const double depth = inside_reach(model, soft, o, 0.0);
        if (c.drift_call != 0)
            c.drift += motion_bound(tool.pieces[c.piece], c.drift_pose, base) +
                       2.0 * std::max(0.0, reach - c.drift_reach) + std::max(0.0, depth - c.drift_depth);
        c.drift_call = call;
        c.drift_pose = base;
        c.drift_reach = reach;
        c.drift_depth = depth;
    };
    // A triangle's `quiet` from what a look at it found: its clearance `clear` (m) added to the
    // set's drift, a picometre under for the rounding of the sums; none where a vertex came
    // within the bounds, unknown where it was not measured.
    auto quiet_until = [](const Workspace::CompliantSet& c, double clear, bool featured) {
        if (featured) return Workspace::kQuietNone;
        return clear > 1e-12 ? c.drift + clear - 1e-12 : Workspace::kQuietUnknown;
    };
    // Whether a constraint normal points within 60 degrees of the push (true without a push).
    const double push_len = glm::length(push);
    auto along_push = [&](const Vec3& n) { return !(push_len > 0.0) || glm::dot(n, push) >= 0.5 * push_len; };
    w.atom_count = 0;
    w.alt_count = 0;
    w.feat_count = 0;
    w.gather_full = false;
    w.tests += w.near_count;
    w.inside_count = 0;
    w.overt_count = 0;
    w.oedge_count = 0;

    // Tool vertices against object features (V-F and its combinations). A ball meets a piece's
    // axis coordinate in an interval no longer than its diameter: only the run of the piece's
    // vertices sorted along its axis that falls in it (a nanometre over, for the rounding of
    // placing them) can pass the sphere test below.
    Vec3 axis_world[kMaxToolPieces];
    Vec3 cross_world[kMaxToolPieces][2];
    for (size_t k = 0; k < tool.pieces.size(); ++k) {
        axis_world[k] = base.orientation * tool.pieces[k].axis;
        cross_world[k][0] = base.orientation * tool.pieces[k].cross_u;
        cross_world[k][1] = base.orientation * tool.pieces[k].cross_w;
    }
    const double axial_slack = 1e-9 + 1e-12 * (glm::length(base.position) + tool.radius_m);
    // A feature plane (an atom whose value is the distance) further than this cannot hold
    // (ZoneCover); 1e300 without drop_covered_atoms: none is left out.
    const double far_plane = model.settings.drop_covered_atoms ? cover.far_plane() : 1e300;
    for (int i = 0; i < w.near_count; ++i) {
        const NearTri& nt = w.near[i];
        const double back = back_of(nt.object), far = reach_of(nt.object);
        const ToolPiece& piece = tool.pieces[nt.piece];
        // A triangle the piece is further than `far` from (by detect's lower bound: in the tissue,
        // the capsules' bound of the gingiva triangles in the piece's box) is that far from every
        // vertex and edge of the piece: no V-F or E-E atom. Its vertices may still face a tool
        // face within the reach (F-V).
        const bool beyond = nt.lower_m > far;
        // Its vertices are no nearer the piece than its bound says, and so over some face plane
        // of the piece by plane_ratio of that (a nanometre under, for the rounding of the planes
        // and the merging of coplanar faces): beyond the reach there, they make no F-V atom.
        const bool faces_beyond = piece.plane_ratio * nt.lower_m > reach + 1e-9;
        // Both (about half the tissue's triangles in a piece's box): nothing more of it is read.
        if (beyond && faces_beyond) continue;
        const ModelObject& obj = model.objects[nt.object];
        const auto& t = obj.mesh.triangles[nt.tri];
        // Only convex object vertices (and mixed ones) and convex edges meet the tool's faces
        // and edges (F-V and E-E below).
        const unsigned corners = obj.topology.triangle_corners[nt.tri];
        if (!faces_beyond)
            for (int k = 0; k < 3; ++k)
                if (corners >> k & 1u) w.overts[w.overt_count++] = obj_feature(nt.object, t[k], nt.piece);
        if (!beyond && corners >> 3 != 0)
            for (int k = 0; k < 3; ++k)
                if (corners >> (3 + k) & 1u)
                    w.oedges[w.oedge_count++] = obj_feature(nt.object, obj.topology.triangle_edges[nt.tri][k], nt.piece);
        if (beyond) continue;
        // A triangle a compliant set gave, clear of the piece's vertices while the set's drift is
        // under its `quiet` (Workspace::CompliantSet): passed over; one that gave a feature, all
        // of the piece's vertices but those `listed` clear of it so long: only those looked at.
        // Else its clearance is measured: how far the nearest vertex is from the tests' bounds,
        // up to kQuietHorizon (the vertices are looked for that much further), and of one that
        // gives a feature, the vertices nearer than that (a piece of more than 64 vertices: none
        // listed, and such a triangle is looked at the next time without a margin).
        // (With RendererSettings::audit_quiet_triangles a quiet one is looked at all the same,
        // to count it where a vertex that is not listed came within the bounds; nothing found
        // of such a vertex is kept.)
        Workspace::CompliantSet* set = nullptr;
        int slot = 0;
        bool measure = false, auditing = false, audit_counted = false;
        uint64_t listed = 0;
        if (nt.memo != 0) {
            set = &w.compliant_sets[(nt.memo >> Workspace::kMemoSlotBits) - 1];
            slot = nt.memo & (Workspace::kCompliantSetSlots - 1);
            add_drift(*set, nt.object);
            const double quiet = set->quiet[slot];
            if (quiet > set->drift) {
                listed = set->listed[slot];
                w.quiet_triangles += listed == 0;
                if (model.settings.audit_quiet_triangles) auditing = true;
                else if (listed == 0) continue;
                set = nullptr;
            }
            measure = set && quiet != Workspace::kQuietNone;
        }
        const bool listed_only = listed != 0 && !auditing;
        const double horizon = measure ? kQuietHorizon : 0.0;
        double clear = horizon;  // the least clearance of a vertex looked at (measure only)
        bool featured = false;   // whether a vertex came within the tests' bounds
        uint64_t near_bits = 0;  // the vertices (by place, under 64) nearer than the horizon (measure)
        // No point further than `far` from the triangle's bounding sphere is within `far` of it.
        const TriangleSphere& ts = obj.topology.triangle_spheres[nt.tri];
        const double sphere = ts.radius + far;
        const double along = glm::dot(axis_world[nt.piece], ts.centre - base.position);
        const double* coords = tool.axial_coords.data() + piece.vertex_begin;
        const uint32_t* order = tool.axial_vertices.data() + piece.vertex_begin;
        const int run_end = int(piece.vertex_count);
        const double run_bottom = along - sphere - horizon - axial_slack;
        const double run_top = along + sphere + horizon + axial_slack;
        // The run's vertices the ball's shadow across the axis may hold, in the run's order: by
        // the slabs for a ball narrow against the piece (ToolPiece::cross_narrow_m), else the
        // whole run. The slabs along the axis the run meets hold every vertex of the run (and a
        // few past its ends, which the loop passes over).
        const double shadow = sphere + horizon + axial_slack;
        const bool by_mask = listed_only || shadow < piece.cross_narrow_m;
        uint64_t candidates = 0;
        int run_lo = 0;
        // The triangle's edges from p0, taken once a vertex first needs the closest point.
        Vec3 e01, e02;
        bool edges_known = false;
        int flat_edges = -1;  // the triangle's flat edges, once asked (flat_edges_of)
        if (listed_only) {
            candidates = listed;
        } else if (by_mask) {
            const Vec3 c = ts.centre - base.position;
            const double cu = glm::dot(cross_world[nt.piece][0], c), cw = glm::dot(cross_world[nt.piece][1], c);
            if (std::isfinite(cu) && std::isfinite(cw) && std::isfinite(along)) {
                const int i0 = piece.cross_cell(0, cu - shadow), i1 = piece.cross_cell(0, cu + shadow);
                const int j0 = piece.cross_cell(1, cw - shadow), j1 = piece.cross_cell(1, cw + shadow);
                candidates = piece.cross_range[0][size_t(i0 * kCrossCells + i1)] &
                             piece.cross_range[1][size_t(j0 * kCrossCells + j1)] &
                             piece.axial_mask(piece.axial_cell(run_bottom), piece.axial_cell(run_top));
            } else {
                candidates = piece.axial_mask(0, kAxialCells - 1);  // every vertex of the piece
            }
        } else {
            // Most runs hold no vertex (the ball is beside the piece's long faces): their slabs
            // say so (an empty run: the loop looks at nothing).
            run_lo = piece.axial_run_empty(run_bottom, run_top) ? run_end : piece.axial_run_start(coords, run_bottom);
        }
        // The triangle as values, read once: held by reference they were loaded again at every
        // vertex, as a record the loop writes might have changed them for all the compiler knew.
        const Vec3 p0 = obj.mesh.vertices[t[0]], p1 = obj.mesh.vertices[t[1]], p2 = obj.mesh.vertices[t[2]];
        const Vec3 n = obj.topology.triangle_normals[nt.tri];
        for (int r = run_lo; by_mask ? candidates != 0 : r < run_end && coords[r] <= run_top; ++r) {
            if (by_mask) {
                r = __builtin_ctzll(candidates);
                if (coords[r] > run_top) break;  // past the run's end, as every later one
                candidates &= candidates - 1;
                if (coords[r] < run_bottom) continue;  // before the run's start
            }
            const int a = int(order[r]);
            const double plane = glm::dot(n, w.tool_world[a] - p0);
            // A vertex out of the plane's band is clear of it by as much, or more.
            if (plane > reach || plane < -back) {
                const double out = std::max(plane - reach, -back - plane);
                clear = std::min(clear, out);
                near_bits |= uint64_t(out < horizon) << (r & 63);
                continue;
            }
            const Vec3 off = w.tool_world[a] - ts.centre;
            const double off2 = glm::dot(off, off);
            if (off2 > sphere * sphere) {
                if (measure && off2 < (sphere + clear) * (sphere + clear))
                    clear = std::min(clear, std::sqrt(off2) - sphere);
                near_bits |= uint64_t(off2 < (sphere + horizon) * (sphere + horizon)) << (r & 63);
                continue;
            }
            if (!edges_known) {
                e01 = p1 - p0;
                e02 = p2 - p0;
                edges_known = true;
            }
            TriClosest c;
            if (!closest_on_triangle_within(w.tool_world[a], p0, p1, p2, e01, e02, far, c)) {
                if (measure) {
                    const double out = glm::length(w.tool_world[a] - c.point) - far;
                    clear = std::min(clear, out);
                    near_bits |= uint64_t(out < horizon) << (r & 63);
                }
                continue;
            }
            const FeatureKey key = feature_key(obj, nt.object, nt.tri, uint32_t(a), c.region);
            // An edge or vertex feature of a compliant object is used only by a vertex outside it
            // (behind none of the faces over it), and left out there when it gives no atom that
            // can hold (leaves_out_far_plane): passed over at once. Such a vertex gives nothing
            // until it comes within far_plane of the triangle, over its face or over one of its
            // flat edges (those are not left out at any distance): it is as clear of the bounds
            // as the least of those ways (far_plane rises with the reach, which the set's drift
            // counts). A triangle whose vertices are all so clear is quiet as one they all miss.
            if (obj.compliant && key.type != 0 &&
                leaves_out_far_plane(model, key, w.tool_world[a], c.distance, far_plane)) {
                if (measure) {
                    const Vec3 foot = w.tool_world[a] - plane * n;  // on the triangle's plane
                    const Vec3 across = foot - c.point;
                    double out = std::min(c.distance - far_plane, std::sqrt(glm::dot(across, across)));
                    if (const int flat = flat_edges_of(obj, nt.tri, flat_edges)) {
                        const Vec3 corners[3] = {p0, p1, p2};
                        for (int k = 0; k < 3; ++k)
                            if (flat >> k & 1) out = std::min(out, distance_to_edge_region(corners, n, foot, k));
                    }
                    out -= 1e-12;  // for the rounding of the sums
                    clear = std::min(clear, out);
                    near_bits |= uint64_t(out < horizon) << (r & 63);
                } else {
                    featured = true;
                    near_bits |= uint64_t(1) << (r & 63);
                }
                continue;
            }
            featured = true;
            near_bits |= uint64_t(1) << (r & 63);
            if (auditing && !(r < 64 && (listed >> r & 1u))) {
                // Counted once a triangle.
                w.quiet_featured += !audit_counted;
                audit_counted = true;
                if (listed == 0) break;
                continue;
            }
            if (obj.compliant) {
                // Sorted out below: the tool may be inside a compliant object.
                if (w.inside_count < kMaxFeatures)
                    w.inside[w.inside_count++] =
                        Inside{key, plane, c.distance, c.region == TriRegion::Face && plane < -kBackFace, glm::dot(n, push)};
                else
                    w.gather_full = true;
            } else if (w.feat_count < kMaxFeatures) {
                w.feats[w.feat_count++] = key;
            } else {
                w.gather_full = true;
            }
        }
        // A triangle with no feature but a vertex nearer the bounds than kListedClearance is
        // listed as one with a feature: it would be measured again within a few ticks.
        if (set && (featured || clear < kListedClearance) && measure && piece.vertex_count <= 64) {
            // Every vertex not listed is at least the horizon clear of the bounds.
            set->quiet[slot] = set->drift + horizon - 1e-12;
            set->listed[slot] = near_bits;
        } else if (set) {
            set->quiet[slot] = quiet_until(*set, clear, featured);
            set->listed[slot] = 0;
        }
    }
    sort_features(w);
    if (w.inside_count > 0) {
        // Features of compliant objects. A vertex outside the object (behind none of the faces
        // over it) is held as anywhere else. A vertex inside, where the object gives way, is held
        // by one face: the one facing the way the object pushes back (the force of the last
        // tick), so that a face it happens to be near -- the far side of a corner, an inner face
        // against a neighbouring object -- does not hold it; without a force, the nearest.
        // Placed by tool vertex (a count per vertex), then each vertex's entries by object, in
        // place (mostly one object: a pass that moves nothing).
        const int nv = int(tool.mesh.vertices.size());
        std::fill(w.inside_first, w.inside_first + nv + 1, 0);
        for (int i = 0; i < w.inside_count; ++i) ++w.inside_first[w.inside[i].key.a + 1];
        for (int a = 0; a < nv; ++a) w.inside_first[a + 1] += w.inside_first[a];
        for (int i = 0; i < w.inside_count; ++i) w.inside_sorted[w.inside_first[w.inside[i].key.a]++] = w.inside[i];
        Inside* const in = w.inside_sorted;
        for (int a = nv; a > 0; --a) w.inside_first[a] = w.inside_first[a - 1];
        w.inside_first[0] = 0;
        for (int a = 0; a < nv; ++a)
            for (int i = w.inside_first[a] + 1; i < w.inside_first[a + 1]; ++i)
                for (int k = i; k > w.inside_first[a] && in[k].key.object < in[k - 1].key.object; --k)
                    std::swap(in[k], in[k - 1]);
        const bool pushed = glm::dot(push, push) > 0.0;
        int i = 0;
        while (i < w.inside_count) {
            int j = i;
            bool inside = false;
            while (j < w.inside_count && in[j].key.a == in[i].key.a && in[j].key.object == in[i].key.object)
                inside |= in[j++].behind;
            if (!inside) {
                // (Those leaves_out_far_plane leaves out were never listed.)
                for (int k = i; k < j; ++k)
                    if (w.feat_count < kMaxFeatures) w.feats[w.feat_count++] = in[k].key;
                    else w.gather_full = true;
            } else {
                int best = -1;
                for (int k = i; k < j; ++k) {
                    const Inside& c = in[k];
                    if (c.key.type != 0 || c.plane > kBackFace) continue;
                    if (best < 0) {
                        best = k;
                        continue;
                    }
                    // The most facing the push, then the highest; of equals, the first in key
                    // order.
                    const Inside& b = in[best];
                    const bool by_facing = pushed && c.facing != b.facing;
                    const bool better = by_facing ? c.facing > b.facing : c.plane > b.plane;
                    const bool worse = by_facing ? c.facing < b.facing : c.plane < b.plane;
                    if (better || (!worse && c.key < b.key)) best = k;
                }
                if (best >= 0 && w.feat_count < kMaxFeatures) w.feats[w.feat_count++] = in[best].key;
                else if (best >= 0) w.gather_full = true;
            }
            i = j;
        }
        sort_features(w);
    }
    for (int i = 0; i < w.feat_count; ++i)
        add_feature_atoms(model, w, w.feats[i], w.tool_world[w.feats[i].a], back_of(w.feats[i].object));
    // What the V-F atoms of each compliant zone cover of the rest (ZoneCover).
    const int vf_count = w.atom_count;
    cover_zones(model, base, w, cover);

    // Convex (and mixed) object vertices against tool faces (F-V, Type 11): outside the face of
    // each piece most in front. One face that has the vertex beyond the reach puts the most in
    // front beyond it too: the face that did so for the piece's last vertex is tried first (its
    // neighbours on the object are near it), and the search stops at the first such face.
    w.overt_count = drop_repeats(w.overts, w.feature_scratch, w.overt_count, w.feature_table);
    const int fv_first = w.atom_count;
    w.alt_made_count = 0;
    int beyond[kMaxToolPieces];
    for (int& f : beyond) f = -1;
    for (int i = 0; i < w.overt_count; ++i) {
        const ModelObject& obj = model.objects[feature_object(w.overts[i])];
        const uint32_t v = feature_id(w.overts[i]);
        const Vec3& p = obj.mesh.vertices[v];
        {
            const int k = feature_piece(w.overts[i]);
            const ToolPiece& piece = tool.pieces[k];
            const int f0 = int(piece.face_begin), f1 = int(piece.face_begin + piece.face_count);
            if (beyond[k] >= 0 && glm::dot(w.face_n[beyond[k]], p) - w.face_d[beyond[k]] > reach) continue;
            int best = -1;
            double best_s = -1e300;
            // With the near cache, the memo's faces while the vertex is within their room: every
            // face off them is further than the tie tolerance below the most in front. Else every
            // face, and the memo made where the loop saw them all.
            const uint64_t memo_key = w.overts[i] + 1;
            Workspace::FaceMemo& memo = w.face_memo[hash_slot(memo_key, Workspace::kFaceMemoBits)];
            const Vec3 local = to_tool * (p - base.position);
            const Vec3 off = local - memo.at;
            const bool memo_on = model.settings.near_cache;
            const bool known = memo_on && memo.key == memo_key && memo.owner == w.owner;
            if (known && memo.count < 0) {
                // Beyond the reach at the last look: mostly still, by the same face.
                const int f = memo.faces[0];
                if (glm::dot(w.face_n[f], p) - w.face_d[f] > reach) {
                    beyond[k] = f;
                    continue;
                }
            }
            const bool from_memo = known && memo.count >= 0 && glm::dot(off, off) <= memo.room * memo.room;
            w.face_searches += !from_memo;
            const int listed = from_memo ? memo.count : f1 - f0;
            for (int j = 0; j < listed; ++j) {
                const int f = from_memo ? int(memo.faces[j]) : f0 + j;
                const double s = glm::dot(w.face_n[f], p) - w.face_d[f];
                w.face_s[f] = s;
                if (s > best_s) {
                    best_s = s;
                    best = f;
                    if (s > reach) break;
                }
            }
            if (best_s > reach) beyond[k] = best;
            if (memo_on && best_s > reach) {
                memo.key = memo_key;
                memo.owner = w.owner;
                memo.count = -1;
                memo.faces[0] = uint16_t(best);
            } else if (memo_on && !from_memo && best >= 0) {
                const double room = std::max(reach, 0.0);
                const double within = best_s - 2.0 * room - model.settings.tie_tol_m - 1e-12;
                int count = 0;
                for (int f = f0; f < f1 && count <= Workspace::kFaceMemoFaces; ++f)
                    if (w.face_s[f] >= within) {
                        if (count < Workspace::kFaceMemoFaces) memo.faces[count] = uint16_t(f);
                        ++count;
                    }
                memo.key = count <= Workspace::kFaceMemoFaces ? memo_key : 0;
                memo.owner = w.owner;
                memo.at = local;
                memo.room = room;
                memo.count = count;
            }
            if (best < 0 || best_s > reach || best_s < -back_of(feature_object(w.overts[i]))) continue;
            // Inside a compliant object: only a vertex pressing the way the object pushes back
            // (the tool face's normal against the push) holds the tool.
            if (obj.compliant && best_s < -kBackFace && !along_push(-w.face_n[best])) continue;
            Atom at;
            at.kind = AtomKind::FaceVertex;
            at.object = feature_object(w.overts[i]);
            at.object_vertex = v;
            at.tool_face = static_cast<uint32_t>(best);
            if (obj.compliant) {
                // Covered, with every alternative (within the tie tolerance of it), by the zone's
                // give: left out.
                const uint16_t z = atom_zone(model, at);
                const double g = std::abs(best_s) + model.settings.tie_tol_m;
                const double foot = glm::length(p - base.position) + g;
                if (compliant_zone(model, at.object, z, true) && -g - cover.motion(foot) > cover.limit(z))
                    continue;
            }
            const int index = w.atom_count;
            // An alternative to an atom that did not fit has nothing to replace.
            if (!add_feature_atom(w, at, w.overts[i])) continue;
            for (int j = 0; j < listed; ++j) {
                const int f = from_memo ? int(memo.faces[j]) : f0 + j;
                if (f == best) continue;
                if (w.face_s[f] >= best_s - model.settings.tie_tol_m && w.alt_made_count < kMaxAtoms) {
                    Alt& alt = w.alt_made[w.alt_made_count++];
                    alt.replace = index;
                    alt.atom = at;
                    alt.atom.tool_face = static_cast<uint32_t>(f);
                }
            }
        }
    }
    order_by_feature(w, fv_first, true);

    // Tool edges against convex object edges (E-E, Type 2) on the dynamic plane of eq. 7.
    w.oedge_count = drop_repeats(w.oedges, w.feature_scratch, w.oedge_count, w.feature_table);
    const int ee_first = w.atom_count;
    // The last edge's object and zone, and their `covered` below.
    int covered_object = -1, covered_zone = -1;
    double covered = 0.0;
    for (int i = 0; i < w.oedge_count; ++i) {
        const ModelObject& obj = model.objects[feature_object(w.oedges[i])];
        const MeshEdge& e = obj.topology.edges[feature_id(w.oedges[i])];
        const Vec3& v0 = obj.mesh.vertices[e.v[0]];
        const Vec3& v1 = obj.mesh.vertices[e.v[1]];
        const ToolPiece& piece = tool.pieces[feature_piece(w.oedges[i])];
        // The tool edges that may come within `far` of the object edge, in the tool's frame, in
        // their order.
        const Vec3 l0 = to_tool * (v0 - base.position), l1 = to_tool * (v1 - base.position);
        const Vec3 d_l = l1 - l0;
        const double e_l = glm::dot(d_l, d_l);
        const double far = reach_of(feature_object(w.oedges[i]));
        // With the near cache (RendererSettings::near_cache), from the memo while it holds (no
        // end of the edge has moved further than its room less the rise of `far`); else the tool
        // edges within `far` plus a room (Workspace::edge_memo_room; none without the cache):
        // those whose boxes meet the edge's box widened by as much, less those further by their
        // closest points (a nanometre over, for the rounding of the frames), kept where the memo
        // has room for them. Every other tool edge is further than `far` from the edge, where
        // edge_pair makes no atom. (Listed by distance, a tissue edge has some 60 % of the tool
        // edges its box met.)
        int hits = 0;
        const bool memo_on = model.settings.near_cache;
        const uint64_t memo_key = w.oedges[i] + 1;
        // Two slots the key may sit in: a pair of edges that share one does not push each other
        // out tick after tick.
        const uint32_t slot = hash_slot(memo_key, Workspace::kEdgeMemoBits);
        Workspace::EdgeHitMemo* const pair[2] = {&w.edge_memo[slot], &w.edge_memo[slot ^ 1u]};
        auto owns = [&](const Workspace::EdgeHitMemo* m) { return m->key == memo_key && m->owner == w.owner; };
        Workspace::EdgeHitMemo* memo = !memo_on ? nullptr : owns(pair[0]) ? pair[0] : owns(pair[1]) ? pair[1] : nullptr;
        const uint16_t* edge_hits = w.edge_hits;
        const double slack =
            memo ? Workspace::edge_memo_room(memo->far) - std::max(0.0, far - memo->far) : -1.0;
        const Vec3 m0 = memo ? l0 - memo->at[0] : Vec3(0.0), m1 = memo ? l1 - memo->at[1] : Vec3(0.0);
        if (slack >= 0.0 && glm::dot(m0, m0) <= slack * slack && glm::dot(m1, m1) <= slack * slack) {
            memo->used = w.gather_clock;
            edge_hits = memo->hits;
            hits = memo->count;
            const double moved2 = std::max(glm::dot(m0, m0), glm::dot(m1, m1));
            if (moved2 > kEdgeRenewShare * kEdgeRenewShare * slack * slack && w.edge_due_count < Workspace::kEdgeDue)
                w.edge_due[w.edge_due_count++] =
                    Workspace::EdgeDue{memo, memo_key, {l0, l1}, far, slack > 0.0 ? std::sqrt(moved2) / slack : 1.0};
        } else {
            ++w.edge_queries;
            hits = edge_hits_within(tool, piece, l0, l1, memo_on ? Workspace::edge_memo_within(far) : far + 1e-9,
                                    w.edge_hits);
            if (memo_on && hits <= Workspace::kEdgeMemoHits) {
                // Its own slot again, else the one used longer ago.
                if (!memo) memo = last_use(*pair[0], w.owner) <= last_use(*pair[1], w.owner) ? pair[0] : pair[1];
                memo->key = memo_key;
                memo->owner = w.owner;
                memo->used = w.gather_clock;
                memo->hold(l0, l1, far, w.edge_hits, hits);
            }
        }
        // Only a pair whose closest points lie inside both edges makes an atom, and most do not.
        // The lines' closest points, taken in the tool's frame on the tool's edges as built
        // (ModelTool::edge_lines), settle that first where they are clearly outside an edge
        // (closest_at_an_end, four pairs at a time by pairs_not_at_an_end): the exact test below
        // would leave the pair. The rounding of the move into the frame moves their parameters far
        // less than the test's margin of 1e-8 over the squared sine of the edges' angle (measured
        // over every pair of the bench scenes' runs: at most 1e-10 at squared sines over 1e-2,
        // 6e-9 between 1e-4 and 1e-3).
        const int open = pairs_not_at_an_end(tool.edge_lines.data() + piece.edge_begin, edge_hits, hits, d_l, l0, e_l,
                                             w.edge_open);
        if (open == 0) continue;
        // The rest of the edge's own quantities, for an edge left a pair. A segment is no closer
        // to the tool edge than the distance from its midpoint less its half length: a cheap bound
        // before the exact closest points, in the tool's frame, with a picometre over for the
        // rounding of the move into it.
        const Vec3 mid_l = 0.5 * (l0 + l1);
        const Vec3 eo = v1 - v0;
        const double eo2 = glm::dot(eo, eo);
        const double near_o = far + 0.5 * glm::length(eo) + 1e-12;
        const Vec3 bisector = obj.topology.triangle_normals[e.tri[0]] + obj.topology.triangle_normals[e.tri[1]];
        // An atom of the pair no further than `covered` from either side of the edge is covered by
        // its zone's give (ZoneCover), as is every pair whose tool edge passes that close to the
        // edge's midpoint (no line is further from the edge than that); 0 where none is. The same
        // for every edge of a zone: kept from the last edge's.
        const uint16_t edge_object = feature_object(w.oedges[i]);
        const uint16_t edge_zone = obj.triangle_zone.empty() ? obj.zone : obj.triangle_zone[e.tri[0]];
        if (edge_object != covered_object || edge_zone != covered_zone) {
            covered_object = edge_object;
            covered_zone = edge_zone;
            covered = compliant_zone(model, edge_object, edge_zone, true)
                          ? std::max(0.0, -cover.limit(edge_zone) - cover.vertex_motion)
                          : 0.0;
        }
        const double covered_l = std::max(0.0, covered - 1e-12);
        for (int h = 0; h < open; ++h) {
            const uint32_t te = piece.edge_begin + w.edge_open[h];
            const ModelTool::EdgeLine& line = tool.edge_lines[te];
            const Vec3 off = mid_l - line.from;
            const double along = std::clamp(glm::dot(off, line.along) * line.inv_length2, 0.0, 1.0);
            const Vec3 gap = off - along * line.along;
            if (glm::dot(gap, gap) > near_o * near_o) continue;
            if (glm::dot(gap, gap) < covered_l * covered_l) continue;
            EdgePair pair;
            if (!edge_pair(w.tool_world[tool.edges[te][0]], w.tool_world[tool.edges[te][1]], v0, eo, eo2, bisector, far,
                           pair) ||
                pair.behind < -back_of(feature_object(w.oedges[i])))
                continue;
            // In front of a compliant object's edge, as in front of a rigid one, only within the
            // reach (`far` reaches further only behind it).
            if (obj.compliant && pair.behind > reach && model.settings.drop_covered_atoms) continue;
            if (std::abs(pair.behind) < covered) continue;
            // Inside a compliant object: only an edge pressed the way the object pushes back
            // holds the tool (not one that is in by going past the side of a corner).
            if (obj.compliant && pair.behind < -kBackFace && !along_push(pair.sign * pair.u / pair.u_length)) continue;
            Atom at;
            at.kind = AtomKind::EdgeEdge;
            at.object = feature_object(w.oedges[i]);
            at.object_edge = feature_id(w.oedges[i]);
            at.tool_edge = static_cast<uint32_t>(te);
            at.sign = pair.sign;
            add_feature_atom(w, at, w.oedges[i]);
        }
    }
    order_by_feature(w, ee_first, false);
    remove_covered_atoms(cover, vf_count, w);
    return !w.gather_full;
}

// A (piece, triangle) pair as one number, never 0 (State::held_planes, Workspace::sat_memo).
uint64_t plane_key(const NearTri& nt) {
    return ((uint64_t(nt.object) << 40) | (uint64_t(nt.tri) << 8) | nt.piece) + 1;
}

// The separating plane at the step's start of a triangle that the atoms let a piece of the tool
// reach: atoms that keep every vertex of the piece (or the triangle's vertices) on its side.
void add_separating_plane(const Model& model, const NearTri& nt, size_t piece, double reach, Workspace& w) {
    const ModelObject& obj = model.objects[nt.object];
    const auto& t = obj.mesh.triangles[nt.tri];
    const Vec3 p[3] = {obj.mesh.vertices[t[0]], obj.mesh.vertices[t[1]], obj.mesh.vertices[t[2]]};
    const ConvexView view = tool_view(model, piece, w.tool_world, w);
    const ToolPiece& tp = model.tool.pieces[piece];
    const SatResult sat = separate_convex_triangle(view, p[0], p[1], p[2]);
    const int nv = view.vertex_count;
    const uint64_t key = plane_key(nt);
    if (sat.kind == 1) {
        const int face = int(tp.face_begin) + sat.index;
        for (int k = 0; k < 3; ++k) {
            const double s = glm::dot(w.face_n[face], p[k]) - w.face_d[face];
            if (s > sat.separation + reach) continue;
            Atom at;
            at.kind = AtomKind::FaceVertex;
            at.object = nt.object;
            at.object_vertex = t[k];
            at.tool_face = static_cast<uint32_t>(face);
            if (w.cand_count < kMaxAtoms) {
                w.cand_key[w.cand_count] = key;
                w.cand[w.cand_count++] = at;
            }
        }
        return;
    }
    // Triangle normal or edge-pair axis: a plane frozen for this step through the triangle's
    // vertex furthest along the axis.
    int vk = 0;
    for (int k = 1; k < 3; ++k)
        if (glm::dot(sat.axis, p[k]) > glm::dot(sat.axis, p[vk])) vk = k;
    const double top = glm::dot(sat.axis, p[vk]);
    for (int a = 0; a < nv; ++a) {
        if (glm::dot(sat.axis, view.vertices[a]) - top > sat.separation + reach) continue;
        Atom at;
        at.kind = AtomKind::FixedAxis;
        at.object = nt.object;
        at.object_triangle = nt.tri;
        at.object_vertex = t[vk];
        at.tool_vertex = tp.vertex_begin + static_cast<uint32_t>(a);
        at.axis = sat.axis;
        if (w.cand_count < kMaxAtoms) {
            w.cand_key[w.cand_count] = key;
            w.cand[w.cand_count++] = at;
        }
    }
}

// The step's coordinates in the frame of the tool at its last graphic pose: y = F^T x with
// F = diag(R0, R0). M of eq. 3 is isotropic in each block, so the energy is the same in either;
// the box of eq. 5 drawn in this frame turns with the tool and the scene, so a rigid motion of the
// whole scene changes nothing (a box on the world axes would).
void to_frame(const Mat3& R0, const double x[6], double y[6]) {
    const Vec3 p = glm::transpose(R0) * Vec3(x[0], x[1], x[2]);
    const Vec3 t = glm::transpose(R0) * Vec3(x[3], x[4], x[5]);
    y[0] = p.x; y[1] = p.y; y[2] = p.z;
    y[3] = t.x; y[4] = t.y; y[5] = t.z;
}

void from_frame(const Mat3& R0, const double y[6], double x[6]) {
    const Vec3 p = R0 * Vec3(y[0], y[1], y[2]);
    const Vec3 t = R0 * Vec3(y[3], y[4], y[5]);
    x[0] = p.x; x[1] = p.y; x[2] = p.z;
    x[3] = t.x; x[4] = t.y; x[5] = t.z;
}

// The local-solution box of eq. 5 about the pass's base (x = 0). The paper's box holds each
// coordinate between 0 and the haptic pose's; TowardHaptic keeps only the side that stops a
// coordinate moving away from the haptic pose and adds, as the default (None) has alone, the
// bound every solution meets anyway, so that the reach of the step stays finite: its energy is at
// most that of x = 0 with the compliant zones as deep as at the base, which is feasible. That
// energy counts the zones' springs (SoftDepths::spring_energy_J): a tool pressed into a yielding
// floor has it to give back, and the floor pushes the tool out, away from a haptic tool still
// deeper, as the hand draws back.
//
// The force-continuity box: with the haptic tool moving dh this tick, a translation x changes the
// offset graphic - haptic by x - dh; holding each |x_j - dh_j| <= |dh_j| + c with c = margin/sqrt(3)
// bounds |x - dh| by |dh| + margin (Minkowski), hence the force change by K_t (|dh| + margin).
// x = 0 (staying) is always inside.
void local_box(const RendererSettings& S, double tool_radius, const double target[6], const Vec3& haptic_motion,
               const Vec3& haptic_rotation, const Vec3& moved, const Vec3& turned, bool limit_rate,
               double recover_m, double spring_energy_J, double lower[6], double upper[6]) {
    const double haptic_turn = glm::length(haptic_rotation);
    const HapticSettings& h = S.haptic;
    double e0 = spring_energy_J * h.weight_translational / h.stiffness_N_per_m;
    for (int j = 0; j < 6; ++j) e0 += 0.5 * (j < 3 ? h.weight_translational : h.weight_rotational) * target[j] * target[j];
    for (int j = 0; j < 6; ++j) {
        const double t = target[j];
        // Every solution has at most the energy of x = 0, which is feasible: no coordinate
        // moves further than this from the haptic pose's value.
        const double slack = std::sqrt(2.0 * e0 / (j < 3 ? h.weight_translational : h.weight_rotational));
        // A last pose inside the tolerance (a graze of up to constraint_tol_m) may need a step
        // away from the haptic pose to come out: then every coordinate gets that much room.
        const double recover = j < 3 ? recover_m : recover_m / tool_radius;
        switch (S.local_box) {
            case LocalBox::Paper:  // between the last pose (0) and the haptic pose
                lower[j] = std::min(0.0, t);
                upper[j] = std::max(0.0, t);
                break;
            case LocalBox::TowardHaptic:  // never away from the haptic pose
                lower[j] = t < 0.0 ? t - slack : 0.0;
                upper[j] = t > 0.0 ? t + slack : 0.0;
                break;
            case LocalBox::None:  // only the energy bound, which every solution meets anyway
                lower[j] = std::min(0.0, t - slack);
                upper[j] = std::max(0.0, t + slack);
                break;
        }
        lower[j] -= recover;
        upper[j] += recover;
        if (limit_rate && j >= 3 && S.force_step_margin_m > 0.0) {
            // The same limit on turning, per tick: the haptic tool's own turn plus the margin
            // over the tool radius (keeps the torque continuous and the step's reach small).
            const double dh = haptic_rotation[j - 3];
            const double c = S.force_step_margin_m / tool_radius / std::sqrt(3.0);
            lower[j] = std::min(std::max(lower[j], dh - std::abs(dh) - c - turned[j - 3]), 0.0);
            upper[j] = std::max(std::min(upper[j], dh + std::abs(dh) + c - turned[j - 3]), 0.0);
        }
        if (limit_rate && j < 3 && S.force_step_margin_m > 0.0) {
            const double dh = haptic_motion[j];
            // The haptic tool's turn moves its points by up to radius * turn: contacts may move
            // that much too.
            const double c = (S.force_step_margin_m + tool_radius * haptic_turn) / std::sqrt(3.0);
            // `moved`: how far earlier passes of this tick have already taken the tool.
            lower[j] = std::max(lower[j], dh - std::abs(dh) - c - moved[j]);
            upper[j] = std::min(upper[j], dh + std::abs(dh) + c - moved[j]);
            // Staying put is always allowed, even when an earlier released pass went past the
            // limit.
            lower[j] = std::min(lower[j], 0.0);
            upper[j] = std::max(upper[j], 0.0);
        }
    }
}

// How far any tool point can move within a box of the step's coordinates (rotation about the
// tool origin), plus the contact distance and room for the tolerance.
double box_reach(const RendererSettings& S, double tool_radius, const double lower[6], const double upper[6]) {
    return piece_reach(S, tool_radius, Vec3(0.0), lower, upper).reach;
}

bool inside_box(const double x[6], const double lower[6], const double upper[6]) {
    for (int j = 0; j < 6; ++j)
        if (x[j] < lower[j] || x[j] > upper[j]) return false;
    return true;
}

// Slack variables for the compliant zones of the candidate's atoms, in the order the atoms meet
// them. A zone whose springs no longer fit holds rigidly (never deeper than its surface).
void assign_slacks(const Model& model, Workspace& w) {
    Slacks& sl = w.slacks;
    sl.zones = 0;
    sl.vars = qp::kPoseVars;
    for (int i = 0; i < w.cand_count; ++i) {
        w.cand_slot[i] = -1;
        if (!model.any_compliant || !model.objects[w.cand[i].object].compliant) continue;
        const uint16_t z = atom_zone(model, w.cand[i]);
        const ModelMaterial& m = zone_material(model, z);
        if (!m.compliant) continue;
        int slot = -1;
        for (int k = 0; k < sl.zones; ++k)
            if (sl.zone[k] == z) slot = k;
        if (slot < 0) {
            if (sl.vars + m.springs > qp::kMaxVars) continue;
            slot = sl.zones++;
            sl.zone[slot] = z;
            sl.first[slot] = sl.vars;
            sl.count[slot] = m.springs;
            sl.depth[slot] = 0.0;
            sl.vars += m.springs;
        }
        w.cand_slot[i] = int8_t(slot);
    }
}

// How far an atom's constraint moves per metre its zone gives way: 1 (every face of the zone along
// its own normal), or for a zone that gives way along a direction d, n . d, at least 0 (n the
// constraint's normal): the zone's surface translates along d, so what did not touch it before
// does not touch it after.
// `grad` is the atom's gradient (its first three entries the constraint's normal).
double give_coefficient(const Model& model, const Atom& a, const double grad[6]) {
    const Vec3& d = model.zone_direction[atom_zone(model, a)];
    if (d.x == 0.0 && d.y == 0.0 && d.z == 0.0) return 1.0;
    return std::max(0.0, grad[0] * d.x + grad[1] * d.y + grad[2] * d.z);
}

// The exact value of an atom whose zone gives way by `depth` (m; a rigid atom: slot < 0): >= 0
// when it holds. One evaluation of the atom either way.
double value_with_give(const Model& model, const Atom& a, const ToolPoseAt& at, int slot, double depth,
                       double* give = nullptr) {
    if (slot < 0) {
        if (give) *give = 0.0;
        return evaluate_atom(model, a, at, nullptr);
    }
    double grad[6];
    const double g = evaluate_atom(model, a, at, grad);
    const double gv = give_coefficient(model, a, grad) * depth;
    if (give) *give = gv;
    return g + gv;
}

// How far the zone of slot `slot` gives way at the slack values `x` (m).
double slot_depth(const Slacks& sl, int slot, const double* x) {
    if (slot < 0) return 0.0;
    double d = 0.0;
    for (int v = sl.first[slot]; v < sl.first[slot] + sl.count[slot]; ++v) d += x[v];
    return d;
}

// How deep the chosen candidate's solution is in each compliant object, and its springs' energy.
SoftDepths best_soft_depths(const Workspace& w) {
    SoftDepths s;
    for (int i = 0; i < w.best_count; ++i)
        if (w.best_slot[i] >= 0) s.add(w.best[i].object, w.best_slacks.depth[w.best_slot[i]]);
    s.spring_energy_J = w.best_spring_energy_J;
    return s;
}

// Depth of a zone in a solution, 0 when it has no slack there.
double zone_depth(const Slacks& sl, uint16_t zone) {
    for (int k = 0; k < sl.zones; ++k)
        if (sl.zone[k] == zone) return sl.depth[k];
    return 0.0;
}

double triangle_zone_depth(const Model& model, const Slacks& sl, const NearTri& nt) {
    const ModelObject& o = model.objects[nt.object];
    if (!o.compliant || sl.zones == 0) return 0.0;
    return zone_depth(sl, o.triangle_zone.empty() ? o.zone : o.triangle_zone[nt.tri]);
}

// The active contacts of a solution for friction: the rows the QP holds, their normal forces
// from its multipliers (W (x - t) = sum lambda a, and the force of eq. 4 is K_t / w_t times the
// translational part) and their materials.
void record_friction(const Model& model, const ToolPoseAt& at, int rows, Workspace& w) {
    FrictionContacts& f = w.friction;
    f.count = 0;
    const HapticSettings& h = model.settings.haptic;
    const double to_force = h.stiffness_N_per_m / h.weight_translational;
    for (int k = 0; k < w.solution.active_count; ++k) {
        const int row = w.solution.active[k];
        if (row < 0 || row >= rows || !(w.solution.multipliers[k] > 0.0)) continue;
        double grad[6];
        evaluate_atom(model, w.cand[row], at, grad);
        const ModelMaterial& m = zone_material(model, atom_zone(model, w.cand[row]));
        f.normal[f.count] = Vec3(grad[0], grad[1], grad[2]);
        f.force_N[f.count] = to_force * w.solution.multipliers[k];
        f.mu_static[f.count] = m.friction_static;
        f.mu_kinetic[f.count] = m.friction_kinetic;
        ++f.count;
    }
}

// A candidate with more atoms than the QP has rows: the most binding (least exact value at x, the
// violated first) become the rows, ties in their order. The warm start follows its atoms.
void order_rows(const Model& model, Workspace& w, const ToolPoseAt& at, const double* x) {
    const int n = w.cand_count;
    for (int i = 0; i < n; ++i) {
        w.order_index[i] = i;
        const int slot = w.cand_slot[i];
        w.order_value[i] = value_with_give(model, w.cand[i], at, slot, slot_depth(w.slacks, slot, x));
    }
    Atom warm_atoms[qp::kVars];
    int warm_count = 0;
    for (int k = 0; k < w.warm.count; ++k)
        if (w.warm.active[k] >= 0 && w.warm.active[k] < n) warm_atoms[warm_count++] = w.cand[w.warm.active[k]];
    // Ties in their order: a sort on (value, index) is the stable sort, without the buffer
    // std::stable_sort allocates.
    std::sort(w.order_index, w.order_index + n, [&](int a, int b) {
        return w.order_value[a] < w.order_value[b] || (w.order_value[a] == w.order_value[b] && a < b);
    });
    for (int i = 0; i < n; ++i) {
        w.order_atoms[i] = w.cand[w.order_index[i]];
        w.order_slots[i] = w.cand_slot[w.order_index[i]];
        w.order_keys[i] = w.cand_key[w.order_index[i]];
    }
    std::copy(w.order_atoms, w.order_atoms + n, w.cand);
    std::copy(w.order_slots, w.order_slots + n, w.cand_slot);
    std::copy(w.order_keys, w.order_keys + n, w.cand_key);
    w.warm.count = 0;
    for (int k = 0; k < warm_count; ++k)
        for (int i = 0; i < qp::kMaxRows; ++i)
            if (w.cand[i].same_as(warm_atoms[k])) {
                w.warm.active[w.warm.count++] = i;
                break;
            }
}

// The separation of a piece (`view`) and near triangle nt is the largest gap between their
// projections over every axis (negative where they overlap), so the gap along any one axis bounds
// it from below. The guard tries two such witnesses before the separating-axis test: the
// triangle's normal and the axis the pair's last test found (kept by a hash of the pair).
Workspace::SatMemo& sat_memo_slot(uint64_t key, Workspace& w) {
    return w.sat_memo[hash_slot(key, Workspace::kSatMemoBits)];
}

// The larger of the two witnesses' gaps, the second only where the first falls short of `floor`.
double separation_witness(const Model& model, const ConvexView& view, const NearTri& nt, double floor,
                          Workspace& w) {
    const ModelObject& obj = model.objects[nt.object];
    const auto& t = obj.mesh.triangles[nt.tri];
    const Vec3 &a = obj.mesh.vertices[t[0]], &b = obj.mesh.vertices[t[1]], &c = obj.mesh.vertices[t[2]];
    int* extremes = w.gap_extremes[nt.piece];
    const double normal = gap_along_axis(view, obj.topology.triangle_normals[nt.tri], a, b, c, extremes);
    if (normal >= floor) return normal;
    const uint64_t key = plane_key(nt);
    const Workspace::SatMemo& memo = sat_memo_slot(key, w);
    if (memo.key != key) return normal;
    return std::max(normal, gap_along_axis(view, memo.axis, a, b, c, extremes));
}

// The separation by the separating-axis test, its axis kept for the pair's next witness; the test
// stops at the first axis whose gap reaches `floor` (separate_convex_triangle_until), so that what
// is returned is the separation where it is under the floor, else a gap of at least the floor.
// (Most pairs the guard tests are separated by more than the floor: one of the piece's faces
// says so, and the rest of the test, most of its cost (the edge pairs), is not needed.)
double separation_test(const Model& model, const ConvexView& view, const NearTri& nt, double floor, Workspace& w) {
    const ModelObject& obj = model.objects[nt.object];
    const auto& t = obj.mesh.triangles[nt.tri];
    const SatResult sat = separate_convex_triangle_until(view, obj.mesh.vertices[t[0]], obj.mesh.vertices[t[1]],
                                                         obj.mesh.vertices[t[2]], floor);
    const uint64_t key = plane_key(nt);
    Workspace::SatMemo& memo = sat_memo_slot(key, w);
    memo.key = key;
    memo.axis = sat.axis;
    return sat.separation;
}

bool contact_is_real(const Model& model, const Atom& a, const ToolPoseAt& at, double give);

// Whether every contact of the candidate's atoms (w.cand, their zones' give in w.slacks) at `at`
// is real: an atom within 2 tolerances of zero whose features meet (contact_is_real).
bool answer_is_real(const Model& model, const Workspace& w, const ToolPoseAt& at) {
    const double tol = model.settings.constraint_tol_m;
    for (int i = 0; i < w.cand_count; ++i) {
        const int slot = w.cand_slot[i];
        double give = 0.0;
        const double depth = slot < 0 ? 0.0 : w.slacks.depth[slot];
        if (value_with_give(model, w.cand[i], at, slot, depth, &give) > 2.0 * tol) continue;
        if (!contact_is_real(model, w.cand[i], at, give)) return false;
    }
    return true;
}

// solve: one candidate set by sequential linearization (re-linearize until exact).

CandidateResult solve_candidate(const Model& model, const Pose& base, const Mat3& frame, const double target[6],
                                const double target_local[6], const double lower[6], const double upper[6],
                                double reach, const Atom* previous, int previous_count, Workspace& w,
                                StepStats& stats, const EnergyLimit& limit) {
    const RendererSettings& S = model.settings;
    const HapticSettings& h = S.haptic;
    CandidateResult r;
    qp::Problem& P = w.problem;
    for (int j = 0; j < 6; ++j) {
        P.weight[j] = j < 3 ? h.weight_translational : h.weight_rotational;
        P.target[j] = target_local[j];
        P.lower[j] = lower[j];
        P.upper[j] = upper[j];
    }
    // A spring's energy 1/2 k s^2 on the scale of eq. 3, where the translational spring of eq. 4
    // (K_t) weighs w_t: so that at the solution the zone gives way by exactly force / k.
    const double spring_scale = h.weight_translational / h.stiffness_N_per_m;
    auto set_slack_vars = [&]() {
        assign_slacks(model, w);
        const Slacks& sl = w.slacks;
        P.vars = sl.vars;
        for (int k = 0; k < sl.zones; ++k) {
            const ModelMaterial& m = zone_material(model, sl.zone[k]);
            for (int j = 0; j < sl.count[k]; ++j) {
                const int v = sl.first[k] + j;
                P.weight[v] = m.stiffness_N_per_m[j] * spring_scale;
                P.target[v] = 0.0;
                P.lower[v] = 0.0;
                P.upper[v] = m.cap_m[j];
            }
        }
    };
    set_slack_vars();
    double x[qp::kMaxVars] = {};
    // Warm start: the rows of the contacts active at the last tick go into the working set first.
    w.warm.count = 0;
    for (int i = 0; i < w.cand_count && i < qp::kMaxRows && w.warm.count < qp::kPoseVars; ++i)
        for (int k = 0; k < previous_count; ++k)
            if (w.cand[i].same_as(previous[k])) {
                w.warm.active[w.warm.count++] = i;
                break;
            }
    // The exact value of atom i with its zone's give: >= 0 when it holds.
    auto value = [&](int i, const ToolPoseAt& at) {
        const int slot = w.cand_slot[i];
        return value_with_give(model, w.cand[i], at, slot, slot_depth(w.slacks, slot, x));
    };
    int guard_rounds = 0;
    bool at_start = true;  // x is the step's start
    for (int it = 0; it < S.max_relinearizations; ++it) {
        const bool linearized_at_start = at_start;
        at_start = false;
        const ToolPoseAt at = tool_pose_at(base, x);
        if (w.cand_count > qp::kMaxRows) order_rows(model, w, at, x);
        const int rows = std::min(w.cand_count, qp::kMaxRows);
        const int vars = w.slacks.vars;
        P.rows = rows;
        for (int i = 0; i < rows; ++i) {
            double grad[6];
            const double g = evaluate_atom(model, w.cand[i], at, grad);
            double gx = 0.0;
            for (int j = 0; j < 6; ++j) gx += grad[j] * x[j];
            // The QP works in the frame of the last graphic pose (x = F y, F = diag(R0, R0)):
            // grad . x = (F^T grad) . y.
            to_frame(frame, grad, P.a[i]);
            // g(x_k) + grad . (x - x_k) + (the zone's springs) >= 0
            P.b[i] = gx - g;
            if (vars > qp::kPoseVars) {
                const int slot = w.cand_slot[i];
                for (int v = qp::kPoseVars; v < vars; ++v) P.a[i][v] = 0.0;
                if (slot >= 0) {
                    const double c = give_coefficient(model, w.cand[i], grad);
                    for (int v = w.slacks.first[slot]; v < w.slacks.first[slot] + w.slacks.count[slot]; ++v) P.a[i][v] = c;
                }
            }
        }
        const qp::Status st = qp::solve(P, S.qp, w.warm.count ? &w.warm : nullptr, w.solution);
        ++stats.qp_solves;
        stats.qp_iterations += w.solution.iterations;
        r.relinearizations = it + 1;
        if (st != qp::Status::Optimal) return r;
        w.warm.count = std::min(w.solution.active_count, qp::kVars);
        for (int k = 0; k < w.warm.count; ++k) w.warm.active[k] = w.solution.active[k];
        if (w.solution.active_count == 0) {
            // Nothing holds the tool: exactly the target (no rounding through the frame).
            for (int j = 0; j < 6; ++j) x[j] = target[j];
            for (int v = qp::kPoseVars; v < vars; ++v) x[v] = 0.0;
        } else {
            from_frame(frame, w.solution.x, x);
            for (int v = qp::kPoseVars; v < vars; ++v) x[v] = std::max(0.0, w.solution.x[v]);
        }

        // The exact constraint error at the new pose: no atom violated, and the atoms the QP
        // holds active really touch (no gap left by the linearization).
        const ToolPoseAt nx = tool_pose_at(base, x);
        double worst = 0.0;
        for (int i = 0; i < w.cand_count; ++i) worst = std::max(worst, -value(i, nx));
        for (int k = 0; k < w.solution.active_count; ++k) {
            const int row = w.solution.active[k];
            if (row < 0 || row >= rows) continue;  // box bounds
            worst = std::max(worst, value(row, nx));
        }
        if (worst > S.constraint_tol_m) continue;
        for (int k = 0; k < w.slacks.zones; ++k) w.slacks.depth[k] = slot_depth(w.slacks, k, x);
        // An answer of no use to the caller (EnergyLimit) is given up before the guard: where the
        // guard passes it is the answer, and the planes the guard adds otherwise hold the tool
        // further from the target.
        if (S.give_up_early && (std::isfinite(limit.any) || std::isfinite(limit.virtual_answer))) {
            const double energy = energy_with_springs(h, P, x, target, vars);
            if (energy > limit.any || (energy > limit.virtual_answer && !answer_is_real(model, w, nx))) return r;
        }

        // Guard: every triangle in reach must be separated from the tool at the new pose (a
        // compliant one: by no more than its zone gives way). The pieces at the new pose are
        // placed in arrays of their own (Workspace::tool_moved, moved_face_n, ...); the start
        // pose's stay in place.
        int missed = 0;
        int missed_tris[kMaxMissed];  // indices into w.near
        // No point of a piece moved further than this from the step's start: a triangle that was
        // further than that from the piece there cannot be reached, nor can one whose separation
        // there (along its separating axis) leaves room for that motion. The separations at the
        // start are found once per pass, on the tool's planes there (still in place here).
        // A compliant object's triangle comes with the capsules' bound (piece_compliant_bound):
        // the distance where the capsules' tangent bounds put it clear of them, else the spheres'
        // bound, which bounds the separation from below where they overlap too (the piece and the
        // triangle lie inside the capsule and the sphere, which overlap at least as deep): where
        // that bound, less the motion, is within the zone's give, the triangle needs no test; and
        // one clear of the piece by more than the motion needs none either.
        const double shift = glm::length(nx.p - base.position), turn = glm::length(Vec3(x[3], x[4], x[5]));
        double piece_moved_by[kMaxToolPieces];
        for (size_t k = 0; k < model.tool.pieces.size(); ++k)
            piece_moved_by[k] = shift + turn * model.tool.pieces[k].radius_m;
        auto bound_settles = [&](const NearTri& nt, double moved_by, double give) {
            return model.objects[nt.object].compliant && nt.lower_m - moved_by >= -(S.constraint_tol_m + give);
        };
        // A separation of at least `floor` at the start spares a triangle the check at the new
        // pose. A compliant triangle (which the tool is often inside) tries the witnesses
        // (separation_witness) and the tapered capsules, and no search: GJK here settled under
        // half of the tissue triangles it was run on, and the check at the new pose settles the
        // rest as cheaply (one the witnesses leave under the floor goes there to the
        // separating-axis test at once). A rigid one tries GJK, and the witnesses where GJK finds
        // them touching. Either way a bound that falls short is kept: the check at the new pose
        // settles the triangle. A compliant triangle's separation at an earlier pose, less the
        // motion since (SeparationMemo), comes first; what is found here is remembered.
        const bool memo = S.near_cache && near_cache_at(w.cache, model, base);
        // The pieces' capsule lines at the start, for the tapers' bound below.
        CapsuleLine lines[kMaxToolPieces];
        for (size_t k = 0; k < model.tool.pieces.size(); ++k)
            if (model.tool.pieces[k].capsule_count > 0)
                lines[k] = capsule_line(model.tool.pieces[k], w.capsule + k * (kToolCapsules + 1));
        // The separation at the start of a triangle not yet measured there, at least its lower
        // bound where that is all the tests below find (left NaN where detect's upper bound is
        // under the floor: the check at the new pose settles it).
        auto separate_at_start = [&](NearTri& nt, double moved_by, double give) {
            const double floor = moved_by - (S.constraint_tol_m + give);
            const bool compliant = model.objects[nt.object].compliant;
            const bool remember = compliant && memo;
            if (remember) {
                const double earlier = near_cache_separation(w.cache, model, nt.object, nt.tri, nt.piece);
                if (earlier >= floor) {
                    nt.separation_m = std::max(earlier, nt.lower_m);
                    return;
                }
            }
            const ConvexView view = tool_view(model, nt.piece, w.tool_world, w);
            const double witness = compliant ? separation_witness(model, view, nt, floor, w) : -1e300;
            if (witness >= floor) {
                nt.separation_m = std::max(witness, nt.lower_m);
                if (remember) near_cache_keep_separation(w.cache, nt.object, nt.tri, nt.piece, nt.separation_m);
                return;
            }
            // Detect's upper bound on the distance here under the floor (a triangle the tool
            // rests on): no bound here spares it the check at the new pose. Left unmeasured for a
            // candidate that moves the tool less.
            if (nt.upper_m < floor) return;
            const ModelObject& obj = model.objects[nt.object];
            const auto& t = obj.mesh.triangles[nt.tri];
            const Vec3 &t0 = obj.mesh.vertices[t[0]], &t1 = obj.mesh.vertices[t[1]], &t2 = obj.mesh.vertices[t[2]];
            if (compliant) {
                // Clear of the floor by the tapered capsules (beside a tapering probe they bound
                // it some tens of micrometres closer than the capsules did in detect), else left
                // with the witnesses' bound.
                const ToolPiece& piece = model.tool.pieces[nt.piece];
                const double taper =
                    piece.capsule_count > 0 && floor > 0.0
                        ? piece_taper_bound(piece, lines[nt.piece], obj.topology.triangle_spheres[nt.tri], t0, t1, t2)
                        : -1e300;
                if (taper >= floor) {
                    nt.separation_m = std::max(taper, nt.lower_m);
                    if (remember) near_cache_keep_separation(w.cache, nt.object, nt.tri, nt.piece, nt.separation_m);
                } else {
                    nt.separation_m = std::max(witness, nt.lower_m);
                }
                return;
            }
            ++w.tests;
            // GJK's gap along its directions, until it reaches the floor (a bound as good as
            // the separation, cheaper) or the distance is found under it; the witnesses' bound
            // where they touch and the floor allows an overlap.
            const Vec3* hint = glm::dot(nt.direction, nt.direction) > 0.0 ? &nt.direction : nullptr;
            const GjkSimplex* warm = nt.simplex.count > 0 ? &nt.simplex : nullptr;
            const DistanceBounds d = convex_triangle_separation(view, t0, t1, t2, floor, floor, hint, warm);
            nt.separation_m = d.separation;
            if (d.separation < floor && !(d.upper < floor))
                nt.separation_m = std::max(d.separation, separation_witness(model, view, nt, floor, w));
        };
        // What this pass leaves unsettled goes on to the check at the new pose (w.guard_open), with
        // its zone's give there: a triangle whose separation here, less the motion, is under that
        // give (or unmeasured).
        int open = 0;
        for (int i = 0; i < w.near_count; ++i) {
            NearTri& nt = w.near[i];
            const double moved_by = piece_moved_by[nt.piece];
            if (nt.lower_m > moved_by) continue;
            const double give = triangle_zone_depth(model, w.slacks, nt);
            if (bound_settles(nt, moved_by, give)) continue;
            if (std::isnan(nt.separation_m)) separate_at_start(nt, moved_by, give);
            if (!(nt.separation_m - moved_by >= -(S.constraint_tol_m + give))) {
                w.guard_open[open] = i;
                w.guard_give[open++] = give;
            }
        }
        // The tool's pieces at the new pose, each placed once a triangle needs it (mostly the tip
        // and its neighbour of the probe's eleven).
        uint32_t moved_placed = 0;
        static_assert(kMaxToolPieces <= 32, "the pieces placed at the new pose are a 32-bit mask");
        auto place_moved = [&](size_t k) {
            if (moved_placed >> k & 1u) return;
            place_tool_piece(model.tool, k, nx.q, nx.p, w.tool_moved, w.moved_face_n, w.moved_face_d, w.moved_capsule);
            w.moved_face_q = nx.q;
            moved_placed |= 1u << k;
        };
        for (int j = 0; j < open && missed < kMaxMissed; ++j) {
            const int i = w.guard_open[j];
            const double give_i = w.guard_give[j];
            const size_t k = w.near[i].piece;
            place_moved(k);
            const ConvexView moved = tool_convex_view(model.tool, k, w.tool_moved, w.moved_face_n, w.moved_face_d,
                                                      &w.moved_face_q, w.moved_capsule);
            // As at the start: a compliant triangle's witnesses before GJK, a rigid one's after.
            const double floor = -(S.constraint_tol_m + give_i);
            const bool compliant = model.objects[w.near[i].object].compliant;
            const double witness = compliant ? separation_witness(model, moved, w.near[i], floor, w) : -1e300;
            if (witness >= floor) continue;
            const ModelObject& obj = model.objects[w.near[i].object];
            const auto& t = obj.mesh.triangles[w.near[i].tri];
            const Vec3 &t0 = obj.mesh.vertices[t[0]], &t1 = obj.mesh.vertices[t[1]], &t2 = obj.mesh.vertices[t[2]];
            // In the tissue a missed triangle mostly has a vertex deep inside the piece, which says
            // so at the cost of a few face planes.
            if (compliant && vertex_deep_inside(moved, t0, t1, t2, floor, &w.deep_rejecting[k])) {
                missed_tris[missed++] = i;
                continue;
            }
            ++w.tests;
            // Separated by at least the floor along some direction: nothing to measure. First the
            // last direction (no search), then GJK from the triangle's normal, the direction that
            // says so at once for the tool resting on the face.
            const Vec3& dir = w.near[i].direction;
            const GjkSimplex* sx = w.near[i].simplex.count > 0 ? &w.near[i].simplex : nullptr;
            if (glm::dot(dir, dir) > 0.0 &&
                convex_triangle_separation(moved, t0, t1, t2, floor, -1e300, &dir, sx, 0).separation >= floor)
                continue;
            // A compliant triangle already under the floor at the start (by its lower bound) goes to
            // the separating-axis test at once, without the search from the normal: the test stops
            // at the first axis whose gap reaches the floor (over the tissue session, 2,000 of its
            // 2,029 such tests; one of the piece's faces mostly says so), and where none does its
            // answer is exact and settles the triangle.
            if (compliant && w.near[i].separation_m < floor) {
                if (separation_test(model, moved, w.near[i], floor, w) < floor) missed_tris[missed++] = i;
                continue;
            }
            if (convex_triangle_separation(moved, t0, t1, t2, floor, -1e300, &obj.topology.triangle_normals[w.near[i].tri],
                                           sx)
                    .separation >= floor)
                continue;
            if ((compliant ? witness : separation_witness(model, moved, w.near[i], floor, w)) < floor &&
                separation_test(model, moved, w.near[i], floor, w) < floor) {
                missed_tris[missed++] = i;
            }
        }
        if (missed == 0) {
            r.ok = true;
            for (int j = 0; j < 6; ++j) r.x[j] = x[j];
            double springs = 0.0;
            r.energy = energy_with_springs(h, P, x, target, vars, &springs);
            r.spring_energy_J = springs / spring_scale;
            r.error = worst;
            r.atom_count = w.cand_count;
            r.from_start = linearized_at_start;
            for (int k = 0; k < w.solution.active_count; ++k) {
                const int row = w.solution.active[k];
                const bool pose_bound = (row >= qp::kBoxLower && row < qp::kBoxLower + qp::kPoseVars) ||
                                        (row >= qp::kBoxUpper && row < qp::kBoxUpper + qp::kPoseVars);
                r.box_held |= pose_bound && w.solution.multipliers[k] > 0.0;
            }
            if (model.any_friction) record_friction(model, nx, rows, w);
            return r;
        }
        if (++guard_rounds > 4) return r;
        for (int m = 0; m < missed; ++m) {
            const NearTri& nt = w.near[missed_tris[m]];
            const int first = w.cand_count;
            add_separating_plane(model, nt, nt.piece, reach, w);
            for (int i = first; i < w.cand_count && w.plane_count < kMaxAtoms; ++i) {
                w.planes_key[w.plane_count] = w.cand_key[i];
                w.planes[w.plane_count++] = w.cand[i];
            }
        }
        set_slack_vars();
        // Start again from the step's start with the added planes.
        for (double& v : x) v = 0.0;
        w.warm.count = 0;
        at_start = true;
    }
    return r;
}

// The world point where an active atom touches.
Vec3 contact_point(const Model& model, const Atom& a, const ToolPoseAt& t) {
    const ModelObject& o = model.objects[a.object];
    switch (a.kind) {
        case AtomKind::VertexFace:
        case AtomKind::FixedAxis: return t.p + t.R * model.tool.mesh.vertices[a.tool_vertex];
        case AtomKind::FaceVertex: return o.mesh.vertices[a.object_vertex];
        case AtomKind::EdgeEdge: {
            const auto& te = model.tool.edges[a.tool_edge];
            const MeshEdge& e = o.topology.edges[a.object_edge];
            const Vec3 a0 = t.p + t.R * model.tool.mesh.vertices[te[0]];
            const Vec3 a1 = t.p + t.R * model.tool.mesh.vertices[te[1]];
            const Vec3& v0 = o.mesh.vertices[e.v[0]];
            const Vec3& v1 = o.mesh.vertices[e.v[1]];
            const SegmentClosest c = closest_segments(a0, a1, v0, v1);
            return v0 + c.t * (v1 - v0);
        }
    }
    return t.p;
}

// The separating planes of the triangles whose planes held the tool at the last tick (those still
// near), as the first of w.planes: the default candidate starts with them, and so every other.
void carry_planes(const Model& model, const State& state, double reach, Workspace& w) {
    // The carried pairs in a small open-addressed table, looked up once per near triangle (so the
    // planes come in the near set's order).
    constexpr int kBits = 8;
    static_assert((1 << kBits) >= 2 * kMaxHeldPlanes, "the table keeps at least half its slots free");
    uint64_t table[1 << kBits] = {};
    // The key's slot, or the empty one where it would go.
    auto slot = [&](uint64_t key) {
        uint32_t h = hash_slot(key, kBits);
        while (table[h] != 0 && table[h] != key) h = (h + 1) & ((1u << kBits) - 1);
        return h;
    };
    for (int i = 0; i < state.held_plane_count; ++i) table[slot(state.held_planes[i])] = state.held_planes[i];
    w.cand_count = 0;
    for (int i = 0; i < w.near_count; ++i) {
        if (!model.objects[w.near[i].object].compliant) continue;
        const uint64_t key = plane_key(w.near[i]);
        if (table[slot(key)] == key) add_separating_plane(model, w.near[i], w.near[i].piece, reach, w);
    }
    std::copy(w.cand, w.cand + w.cand_count, w.planes);
    std::copy(w.cand_key, w.cand_key + w.cand_count, w.planes_key);
    w.plane_count = w.cand_count;
}

// The candidate just solved (w.cand and its solution `cr`) becomes the chosen one (w.best).
void keep_candidate(const Model& model, const CandidateResult& cr, Workspace& w, StepStats& stats, double x_out[6]) {
    for (int j = 0; j < 6; ++j) x_out[j] = cr.x[j];
    stats.relinearizations = cr.relinearizations;
    stats.constraint_error_m = cr.error;
    w.best_box_held = cr.box_held;
    w.best_energy = cr.energy;
    w.best_spring_energy_J = cr.spring_energy_J;
    w.best_count = w.cand_count;
    std::copy(w.cand, w.cand + w.cand_count, w.best);
    std::copy(w.cand_slot, w.cand_slot + w.cand_count, w.best_slot);
    std::copy(w.cand_key, w.cand_key + w.cand_count, w.best_key);
    w.best_slacks = w.slacks;
    if (model.any_friction) w.best_friction = w.friction;
}

// solve + select: every candidate set within the box; the feasible one of least energy wins
// (ties keep the lower index, for determinism). Leaves the winner's atoms in w.best.
//
// A candidate swaps one atom of the default set for an alternative, and starts with the separating
// planes the guard gave the default set (the triangles it missed are as near for every candidate).
// Where the default set's answer is the first QP from the step's start over its atoms and planes,
// exact, with that atom holding nothing (not active, or active with no multiplier), the QP without
// the atom has the same solution, and adding the alternative cannot lower its energy: the
// candidate's own first QP, which differs from that one by the swap alone, has no less energy, and
// what the guard adds to it can only raise it. It cannot win, and is not solved. (Where the atoms
// outnumber the QP's rows and the most binding are taken, the swap can also move the least binding
// row out; that row held nothing in the cases measured.)
//
// The default set starts with the planes the last tick carried (carry_planes); where they leave
// it no answer, it is solved again without them.
bool solve_candidates(const Model& model, const Pose& base, const Mat3& frame, const double target[6],
                      const double target_local[6], const double lower[6], const double upper[6], double reach,
                      const State& state, Workspace& w, StepStats& stats, double x_out[6]) {
    const int candidates = std::min(1 + w.alt_count, std::max(1, model.settings.max_candidates));
    double best_energy = 1e300;
    bool found = false;
    // Whether each atom of the default set holds at its solution (when that solution qualifies).
    bool plain_default = false;
    bool holds[kMaxAtoms];
    w.plane_count = 0;
    if (model.settings.carry_planes && state.held_plane_count > 0) carry_planes(model, state, reach, w);
    // The default candidate's, w.planes[0, shared_planes): the carried ones, then those its guard adds.
    int shared_planes = w.plane_count;
    // Candidate c: the default set's atoms (after the first, one swapped for its alternative),
    // then the first `planes` of w.planes.
    // After the first, a candidate is kept only with less energy than the best so far: one whose
    // answer has no less is given up before its guard.
    auto solve = [&](int c, int planes) {
        EnergyLimit limit;
        if (c > 0) limit.any = std::nextafter(best_energy, 0.0);
        w.cand_count = w.atom_count;
        std::copy(w.atoms, w.atoms + w.atom_count, w.cand);
        std::fill(w.cand_key, w.cand_key + w.atom_count, uint64_t(0));
        if (c > 0) w.cand[w.alts[c - 1].replace] = w.alts[c - 1].atom;
        for (int i = 0; i < planes && w.cand_count < kMaxAtoms; ++i) {
            w.cand_key[w.cand_count] = w.planes_key[i];
            w.cand[w.cand_count++] = w.planes[i];
        }
        ++stats.candidates;
        return solve_candidate(model, base, frame, target, target_local, lower, upper, reach, state.active,
                               state.active_count, w, stats, limit);
    };
    for (int c = 0; c < candidates; ++c) {
        if (c > 0 && plain_default && model.settings.skip_idle_candidates && !holds[w.alts[c - 1].replace]) continue;
        CandidateResult cr = solve(c, shared_planes);
        if (c == 0 && !cr.ok && shared_planes > 0) {
            // The carried planes leave the default set no answer: it is solved as it comes.
            w.plane_count = 0;
            cr = solve(0, 0);
        }
        if (c == 0) shared_planes = w.plane_count;
        if (c == 0 && cr.ok && cr.from_start) {
            // The rows are the atoms and planes, in their order or (more of them than rows) the
            // most binding first: an atom holds where a row the same as it does.
            plain_default = true;
            std::fill(holds, holds + w.atom_count, false);
            for (int k = 0; k < w.solution.active_count; ++k) {
                const int row = w.solution.active[k];
                if (row < 0 || row >= w.cand_count || !(w.solution.multipliers[k] > 0.0)) continue;
                if (w.cand_count == w.atom_count && w.cand_count <= qp::kMaxRows) {
                    holds[row] = true;
                    continue;
                }
                for (int i = 0; i < w.atom_count; ++i)
                    if (w.atoms[i].same_as(w.cand[row])) holds[i] = true;
            }
        }
        if (cr.ok && cr.energy < best_energy) {
            best_energy = cr.energy;
            found = true;
            keep_candidate(model, cr, w, stats, x_out);
        }
    }
    if (found) stats.atoms = w.best_count;
    return found;
}

// Whether some triangle of object o comes within `within` of world point p.
bool near_surface(const ModelObject& o, const Vec3& p, double within) {
    Aabb box;
    box.grow(p);
    box.inflate(within);
    bool hit = false;
    o.bvh.query(box, [&](uint32_t tri) {
        const auto& t = o.mesh.triangles[tri];
        hit = closest_on_triangle(p, o.mesh.vertices[t[0]], o.mesh.vertices[t[1]], o.mesh.vertices[t[2]]).distance <= within;
        return !hit;
    });
    return hit;
}

// Whether the piece of the tool holding tool vertex `v` comes within `within` of triangle `tri`
// of object o, the tool at pose `at` (measured in the tool's frame).
bool piece_meets_triangle(const Model& model, uint32_t v, const ModelObject& o, uint32_t tri, const ToolPoseAt& at,
                          double within) {
    const ModelTool& tool = model.tool;
    const ToolPiece& piece = tool.pieces[tool.vertex_piece[v]];
    const auto& t = o.mesh.triangles[tri];
    const Mat3 Rt = glm::transpose(at.R);
    const Vec3 a = Rt * (o.mesh.vertices[t[0]] - at.p), b = Rt * (o.mesh.vertices[t[1]] - at.p),
               c = Rt * (o.mesh.vertices[t[2]] - at.p);
    return convex_triangle_distance(tool.mesh.vertices.data() + piece.vertex_begin, int(piece.vertex_count), a, b, c,
                                    within, 0.01 * within, 64, nullptr)
               .lower <= within;
}

// Whether world point m lies on the contact: on the tool's surface and on an object's surface,
// both within `tol` (a compliant object's surface within tol + give: the tool is that far in).
bool on_contact(const Model& model, const Workspace& w, const Vec3& m, double tol, double give) {
    // On the surface of some piece (inside the others or not: a point of the union's surface lies
    // on one piece's surface).
    bool on_tool = false;
    for (const ToolPiece& piece : model.tool.pieces) {
        // The most m is in front of a face; once over tol, m is off this piece's surface.
        double inside = -1e300;
        for (uint32_t f = piece.face_begin; f < piece.face_begin + piece.face_count && inside <= tol; ++f)
            inside = std::max(inside, glm::dot(w.face_n[f], m) - w.face_d[f]);
        if (std::abs(inside) <= tol) {
            on_tool = true;
            break;
        }
    }
    if (!on_tool) return false;
    for (const ModelObject& o : model.objects)
        if (near_surface(o, m, o.compliant ? tol + give : tol)) return true;
    return false;
}

// Contact regions: two contacts belong to one region when the midpoint of their contact points
// is itself on the contact (a face lying on a face is one region; a tip on a floor and a shaft on
// an edge are two). Needs the tool planes of the solution pose in the workspace.
int count_regions(const Model& model, const Workspace& w, const Atom* atoms, int count, const ToolPoseAt& at,
                  double tol, double give) {
    constexpr int kMax = kMaxActiveAtoms;
    Vec3 point[kMax];
    int parent[kMax];
    const int n = std::min(count, kMax);
    for (int i = 0; i < n; ++i) {
        point[i] = contact_point(model, atoms[i], at);
        parent[i] = i;
    }
    auto find = [&](int i) {
        while (parent[i] != i) i = parent[i] = parent[parent[i]];
        return i;
    };
    for (int i = 0; i < n; ++i) {
        for (int j = i + 1; j < n; ++j) {
            if (find(i) == find(j)) continue;
            const Vec3 m = 0.5 * (point[i] + point[j]);
            if (glm::length(point[i] - point[j]) <= tol || on_contact(model, w, m, tol, give)) parent[find(i)] = find(j);
        }
    }
    int regions = 0;
    for (int i = 0; i < n; ++i)
        if (find(i) == i) ++regions;
    return regions;
}

// The exact value of the chosen candidate's atom i with its zone's give (`give` receives the give).
double best_value(const Model& model, const Workspace& w, int i, const ToolPoseAt& at, double* give = nullptr) {
    const int slot = w.best_slot[i];
    return value_with_give(model, w.best[i], at, slot, slot < 0 ? 0.0 : w.best_slacks.depth[slot], give);
}

// The contacts of the chosen atom set at x: an atom within 2 tolerances of zero is touching; it
// is a real contact when its features themselves meet, and a virtual one when it holds the tool
// on an extended plane (a vertex past the edge of the face whose plane it touches, edges whose
// lines meet beyond their ends).
struct ContactCheck {
    bool real = false;
    bool virtual_only = false;  // touching somewhere, but nowhere really
    bool any_virtual = false;
};

// The distance between the features of atom `a` with the tool at `at`: its tool vertex and object
// triangle, its object vertex and the tool's surface, its two edges. For an object vertex the
// tool's triangles are searched until one's distance `d` satisfies `enough(d)`, which must hold
// for every distance below one it holds for: the answer then says the same of the least
// distance. Those on the atom's own face plane are searched first, where the vertex mostly
// touches.
template <class Enough>
double feature_distance(const Model& model, const Atom& a, const ToolPoseAt& at, Enough&& enough) {
    const ModelTool& tool = model.tool;
    const ModelObject& o = model.objects[a.object];
    if (a.kind == AtomKind::VertexFace || a.kind == AtomKind::FixedAxis) {
        const auto& t = o.mesh.triangles[a.object_triangle];
        return closest_on_triangle(at.p + at.R * tool.mesh.vertices[a.tool_vertex], o.mesh.vertices[t[0]],
                                   o.mesh.vertices[t[1]], o.mesh.vertices[t[2]]).distance;
    }
    if (a.kind == AtomKind::FaceVertex) {
        double d = 1e300;
        const Vec3 v = glm::transpose(at.R) * (o.mesh.vertices[a.object_vertex] - at.p);  // tool frame
        auto to_triangle = [&](const std::array<uint32_t, 3>& t) {
            return closest_on_triangle(v, tool.mesh.vertices[t[0]], tool.mesh.vertices[t[1]],
                                       tool.mesh.vertices[t[2]]).distance;
        };
        // A triangle whose plane is further from the vertex than the least distance so far is no
        // nearer: passed over, the least stays the same (and `enough` already said no to it). The
        // margin, 1e-13 m and 1e-9 of the distance, is some thousand times the rounding of either
        // distance in the tool's frame.
        auto further = [&](size_t t) {
            const Vec3& t0 = tool.mesh.vertices[tool.mesh.triangles[t][0]];
            return std::abs(glm::dot(tool.topology.triangle_normals[t], v - t0)) > d + 1e-9 * d + 1e-13;
        };
        const Vec3& fn = tool.face_normals[a.tool_face];
        const size_t n = tool.mesh.triangles.size();
        for (size_t t = 0; t < n; ++t)
            if (glm::dot(tool.topology.triangle_normals[t], fn) > 1.0 - 1e-9 && !further(t)) {
                d = std::min(d, to_triangle(tool.mesh.triangles[t]));
                if (enough(d)) return d;
            }
        for (size_t t = 0; t < n; ++t) {
            if (further(t)) continue;
            d = std::min(d, to_triangle(tool.mesh.triangles[t]));
            if (enough(d)) return d;
        }
        return d;
    }
    const auto& te = tool.edges[a.tool_edge];
    const MeshEdge& e = o.topology.edges[a.object_edge];
    return closest_segments(at.p + at.R * tool.mesh.vertices[te[0]], at.p + at.R * tool.mesh.vertices[te[1]],
                            o.mesh.vertices[e.v[0]], o.mesh.vertices[e.v[1]]).distance;
}

// Whether touching atom `a` (within 2 tolerances of zero at `at`, `give` into its compliant zone)
// is a real contact: its features themselves meet. It is virtual when it holds the tool on an
// extended plane.
bool contact_is_real(const Model& model, const Atom& a, const ToolPoseAt& at, double give) {
    const double tol = model.settings.constraint_tol_m;
    const ModelObject& o = model.objects[a.object];
    // Without give the contact is real when the features are within the tolerance.
    // In a compliant zone the tool is `give` inside the surface it touches. That surface is
    // every face of the zone moved in, not one face's plane, so the contact is real too when
    // the feature is deeper than `give` in the other, or when the tool vertex is within
    // `give` of any face of the object. A separating plane of the guard holds the piece off
    // its triangle: real when the piece meets the triangle, wherever the vertex on the plane
    // is (a long tool's edge laid across the face).
    const bool deeper_counts = o.compliant && give > 0.0;
    auto meets = [&](double d) { return std::abs(d - give) <= 10.0 * tol || (deeper_counts && d < give); };
    // Without give, or where deeper counts, the test holds for every distance below one it holds
    // for: the search may stop at the first distance it holds for.
    const bool may_stop = give == 0.0 || deeper_counts;
    bool real = meets(feature_distance(model, a, at, [&](double d) { return may_stop && meets(d); }));
    if (!real && deeper_counts) {
        if (a.kind == AtomKind::VertexFace || a.kind == AtomKind::FixedAxis)
            real = near_surface(o, at.p + at.R * model.tool.mesh.vertices[a.tool_vertex], give + 10.0 * tol);
        if (!real && a.kind == AtomKind::FixedAxis)
            real = piece_meets_triangle(model, a.tool_vertex, o, a.object_triangle, at, give + 10.0 * tol);
    }
    return real;
}

// Whether the tool at `at` is within the contact distance of a rigid object's feature that a
// gathered atom of the chosen set holds it off: in contact, as the step counts contacts, though
// not touching to the tolerance, so not to be released. (A compliant triangle's separating plane
// near the tool does not count: the tool can be near the plane far from its triangle.)
bool within_contact_distance(const Model& model, const Workspace& w, const ToolPoseAt& at) {
    const double within = model.settings.contact_distance_m;
    for (int i = 0; i < w.best_count; ++i)
        if (w.best_key[i] == 0 && !model.objects[w.best[i].object].compliant && best_value(model, w, i, at) <= within &&
            feature_distance(model, w.best[i], at, [within](double d) { return d <= within; }) <= within)
            return true;
    return false;
}

ContactCheck check_contacts(const Model& model, const Pose& base, const double x[6], const Workspace& w) {
    const double tol = model.settings.constraint_tol_m;
    const ToolPoseAt at = tool_pose_at(base, x);
    ContactCheck c;
    bool touching = false;
    for (int i = 0; i < w.best_count; ++i) {
        double give = 0.0;
        if (best_value(model, w, i, at, &give) > 2.0 * tol) continue;
        touching = true;
        if (contact_is_real(model, w.best[i], at, give)) c.real = true;
        else c.any_virtual = true;
    }
    c.virtual_only = touching && !c.real;
    return c;
}

// Coulomb friction on the chosen solution, inside the same optimization: the contacts' normals
// and normal forces (from the QP's multipliers) give the tangent space and the limits
// mu_s N and mu_k N of the tangential force. The graphic tool sticks where it was at the last
// tick while holding it there takes at most the static limit, and slides otherwise, holding the
// tangential force at the kinetic limit; once sliding it slides while the kinetic limit is
// exceeded, so the switch does not chatter. The chosen target's tangential part is moved
// accordingly and the candidate solved again (exact constraints, guard and force-continuity box
// as every solve), so friction never lets the tool into an object. The friction of turning is
// left out. Returns false when nothing changed.
bool apply_friction(const Model& model, const State& state, const Pose& base, const Pose& haptic, const Mat3& frame,
                    const Vec3 motion_local[4], double reach, double x_sol[6], Workspace& w, StepStats& stats) {
    const FrictionContacts f = w.best_friction;
    double normal = 0.0, limit_s = 0.0, limit_k = 0.0;
    Vec3 e[3];
    int rank = 0;
    for (int k = 0; k < f.count; ++k) {
        normal += f.force_N[k];
        limit_s += f.mu_static[k] * f.force_N[k];
        limit_k += f.mu_kinetic[k] * f.force_N[k];
        Vec3 v = f.normal[k];
        for (int i = 0; i < rank; ++i) v -= glm::dot(v, e[i]) * e[i];
        const double len = glm::length(v);
        if (len > 1e-6 && rank < 3) e[rank++] = v / len;
    }
    stats.normal_force_N = normal;
    stats.friction_static_limit_N = limit_s;
    stats.friction_kinetic_limit_N = limit_k;
    if (!(limit_s > 0.0) || rank >= 3) return false;  // no friction, or no way to slide
    auto tangential = [&](Vec3 v) {
        for (int i = 0; i < rank; ++i) v -= glm::dot(v, e[i]) * e[i];
        return v;
    };
    const double K = model.settings.haptic.stiffness_N_per_m;
    // The graphic tool's tangential offset from the haptic tool if it stays where it was.
    const Vec3 hold = tangential(state.graphic.position - haptic.position);
    const double pull_N = K * glm::length(hold);
    const bool slide = state.sliding ? pull_N > limit_k * (1.0 + 1e-9) : pull_N > limit_s;
    stats.sliding = slide;
    const Vec3 offset = slide ? hold * (limit_k / pull_N) : hold;

    double target[6], target_local[6], lower[6], upper[6];
    const Vec3 dp = haptic.position + offset - base.position;
    const Vec3 dt = quat_log(haptic.orientation * glm::conjugate(base.orientation));
    target[0] = dp.x; target[1] = dp.y; target[2] = dp.z;
    target[3] = dt.x; target[4] = dt.y; target[5] = dt.z;
    to_frame(frame, target, target_local);
    const double radius = std::max(model.tool.radius_m, 1e-6);
    local_box(model.settings, radius, target_local, motion_local[0], motion_local[1], motion_local[2],
              motion_local[3], true, 0.0, w.soft.spring_energy_J, lower, upper);
    w.cand_count = w.best_count;
    std::copy(w.best, w.best + w.best_count, w.cand);
    std::copy(w.best_key, w.best_key + w.best_count, w.cand_key);
    const CandidateResult cr = solve_candidate(model, base, frame, target, target_local, lower, upper, reach,
                                               state.active, state.active_count, w, stats, EnergyLimit{});
    ++stats.candidates;
    if (!cr.ok) return false;
    for (int j = 0; j < 6; ++j) x_sol[j] = cr.x[j];
    w.best_spring_energy_J = cr.spring_energy_J;
    w.best_count = w.cand_count;
    std::copy(w.cand, w.cand + w.cand_count, w.best);
    std::copy(w.cand_slot, w.cand_slot + w.cand_count, w.best_slot);
    std::copy(w.cand_key, w.cand_key + w.cand_count, w.best_key);
    w.best_slacks = w.slacks;
    return true;
}

// A probe sliding over a dense mesh often ends a tick with a vertex slid past the edge of the
// face whose plane holds it, or an object vertex slid off the tool face whose plane holds it: a
// virtual contact, which another pass of the stages would take round the feature. Within the
// pass, more cheaply: each such atom (a gathered V-F, F-V or E-E atom or feature plane of a rigid
// object) is swapped for what gather would find at the solution -- the atoms of the features the
// tool vertex faces among the pass's near triangles, the tool face the object vertex is most in
// front of, and for edges whose lines meet beyond an end, that end's vertex -- and the set is
// solved again in the same box, with the same guard, up to kRescueRounds times while the answer
// still has such contacts. Across a convex feature the free space is the union of its faces'
// half-spaces, and the answer held on the slid-past plane meets the swapped-in constraint there
// (to the tolerance), so each round's answer has no more energy than the tolerance allows; it
// becomes the chosen one. A round whose answer has more (the swapped-in plane holds the tool
// back, as a corner's plane from where the tool started) ends the rescue, as does one still
// virtual without less energy. Where contacts stay virtual, the next pass takes on the answer
// reached (the guard's planes and compliant objects are left to it).
constexpr int kRescueRounds = 3;

void rescue_virtual(const Model& model, const Pose& base, const Mat3& frame, const double target[6],
                    const double target_local[6], const double lower[6], const double upper[6], double reach,
                    const State& state, Workspace& w, StepStats& stats, double x_sol[6]) {
    const double tol = model.settings.constraint_tol_m;
    const ModelTool& tool = model.tool;
    // The atoms swapped out so far: one that comes back (a vertex sent to and fro across a
    // valley of the surface, each face's plane holding it over the other) is held with the one
    // it would replace, as both faces of a concave edge hold a vertex in the valley (eq. 8).
    constexpr int kMaxGone = 16;
    Atom gone[kMaxGone];
    int gone_count = 0;
    for (int round = 0; round < kRescueRounds; ++round) {
        const ToolPoseAt at = tool_pose_at(base, x_sol);
        // The chosen set's real and untouching atoms stay; the virtual ones are swapped.
        constexpr int kMaxSwapped = 8;
        int swapped[kMaxSwapped];
        int swap_count = 0;
        w.cand_count = 0;
        for (int i = 0; i < w.best_count; ++i) {
            double give = 0.0;
            const Atom& a = w.best[i];
            if (best_value(model, w, i, at, &give) > 2.0 * tol || contact_is_real(model, a, at, give)) {
                w.cand_key[w.cand_count] = w.best_key[i];
                w.cand[w.cand_count++] = a;
                continue;
            }
            const bool swappable = w.best_key[i] == 0 && !model.objects[a.object].compliant;
            if (!swappable || swap_count == kMaxSwapped) return;
            swapped[swap_count++] = i;
        }
        if (swap_count == 0) return;  // a round's answer with a virtual contact that cannot be swapped
        auto append = [&](const Atom& a) {
            for (int j = 0; j < w.cand_count; ++j)
                if (w.cand[j].same_as(a)) return;
            if (w.cand_count == kMaxAtoms) return;
            w.cand_key[w.cand_count] = 0;
            w.cand[w.cand_count++] = a;
        };
        // How far behind a rigid object's face or edge a tool feature still faces it (only rigid
        // atoms are swapped).
        const double rigid_back = back_face(model.settings, false);
        // What takes a swapped atom's place.
        constexpr int kMaxReplacing = 16;
        Atom replacing[kMaxReplacing];
        int replacing_count = 0;
        // The atoms of the features tool vertex tv faces now, among the near triangles of its
        // piece, as gather finds them (added after w.atoms and taken from there).
        auto vertex_atoms = [&](uint32_t tv) {
            const Vec3 wa = at.p + at.R * tool.mesh.vertices[tv];
            constexpr int kMaxKeys = 32;
            FeatureKey keys[kMaxKeys];
            int key_count = 0;
            for (int i = 0; i < w.near_count; ++i) {
                const NearTri& nt = w.near[i];
                const ModelObject& obj = model.objects[nt.object];
                if (nt.piece != tool.vertex_piece[tv] || obj.compliant) continue;
                const auto& t = obj.mesh.triangles[nt.tri];
                const Vec3& p0 = obj.mesh.vertices[t[0]];
                const double plane = glm::dot(obj.topology.triangle_normals[nt.tri], wa - p0);
                if (plane > reach || plane < -rigid_back) continue;
                const TriClosest c = closest_on_triangle(wa, p0, obj.mesh.vertices[t[1]], obj.mesh.vertices[t[2]]);
                if (c.distance > reach) continue;
                if (key_count == kMaxKeys) return false;
                keys[key_count++] = feature_key(obj, nt.object, nt.tri, tv, c.region);
            }
            std::sort(keys, keys + key_count);
            key_count = int(std::unique(keys, keys + key_count) - keys);
            const int atom_count = w.atom_count, alt_count = w.alt_count;
            const bool gather_full = w.gather_full;
            for (int k = 0; k < key_count; ++k) add_feature_atoms(model, w, keys[k], wa, rigid_back);
            bool fits = true;
            for (int k = atom_count; k < w.atom_count; ++k) {
                if (replacing_count < kMaxReplacing) replacing[replacing_count++] = w.atoms[k];
                else fits = false;
            }
            w.atom_count = atom_count;
            w.alt_count = alt_count;
            w.gather_full = gather_full;
            return fits;
        };
        // The F-V atom of object vertex ov against the face of piece k it is most in front of now.
        auto face_atom = [&](uint16_t object, uint32_t ov, size_t k) {
            const ToolPiece& piece = tool.pieces[k];
            const Vec3 v = glm::transpose(at.R) * (model.objects[object].mesh.vertices[ov] - at.p);
            Atom f;
            f.kind = AtomKind::FaceVertex;
            f.object = object;
            f.object_vertex = ov;
            double best_s = -1e300;
            for (uint32_t face = piece.face_begin; face < piece.face_begin + piece.face_count; ++face) {
                const double sf = glm::dot(tool.face_normals[face], v) - tool.face_offsets[face];
                if (sf > best_s) {
                    best_s = sf;
                    f.tool_face = face;
                }
            }
            return f;
        };
        for (int s = 0; s < swap_count; ++s) {
            const Atom& a = w.best[swapped[s]];
            replacing_count = 0;
            if (a.kind == AtomKind::FaceVertex) {
                // The tool face of the same piece the object vertex is most in front of now.
                size_t k = 0;
                while (k + 1 < tool.pieces.size() && a.tool_face >= tool.pieces[k].face_begin + tool.pieces[k].face_count) ++k;
                const Atom f = face_atom(a.object, a.object_vertex, k);
                if (f.tool_face == a.tool_face) return;
                replacing[replacing_count++] = f;
            } else if (a.kind == AtomKind::EdgeEdge) {
                // The edges' lines meet beyond an end: the end's vertex holds the tool there, as
                // gather gives it (the tool's end by its features, the object's convex end by
                // the tool face it is in front of).
                const ModelObject& obj = model.objects[a.object];
                const auto& te = tool.edges[a.tool_edge];
                const MeshEdge& e = obj.topology.edges[a.object_edge];
                const SegmentClosest sc =
                    closest_segments(at.p + at.R * tool.mesh.vertices[te[0]], at.p + at.R * tool.mesh.vertices[te[1]],
                                     obj.mesh.vertices[e.v[0]], obj.mesh.vertices[e.v[1]]);
                const bool tool_end = sc.s <= 0.0 || sc.s >= 1.0, object_end = sc.t <= 0.0 || sc.t >= 1.0;
                if (!tool_end && !object_end) return;
                if (tool_end && !vertex_atoms(te[sc.s <= 0.0 ? 0 : 1])) return;
                if (object_end) {
                    const uint32_t ov = e.v[sc.t <= 0.0 ? 0 : 1];
                    const Convexity cv = obj.topology.vertex_convexity[ov];
                    if ((cv == Convexity::Convex || cv == Convexity::Mixed) && replacing_count < kMaxReplacing)
                        replacing[replacing_count++] = face_atom(a.object, ov, tool.vertex_piece[te[0]]);
                    // And the tool edge against the vertex's other convex edges, as gather pairs
                    // them: a tool edge laid across a ridge of short edges slides from one to the
                    // next.
                    const Vec3 a0 = at.p + at.R * tool.mesh.vertices[te[0]];
                    const Vec3 a1 = at.p + at.R * tool.mesh.vertices[te[1]];
                    const uint32_t* offsets = obj.topology.vertex_edge_offsets.data();
                    for (uint32_t j = offsets[ov]; j < offsets[ov + 1]; ++j) {
                        const uint32_t oe = obj.topology.vertex_edges[j];
                        const MeshEdge& next = obj.topology.edges[oe];
                        if (oe == a.object_edge || next.convexity != Convexity::Convex) continue;
                        const Vec3& v0 = obj.mesh.vertices[next.v[0]];
                        const Vec3 eo = obj.mesh.vertices[next.v[1]] - v0;
                        const Vec3 bisector =
                            obj.topology.triangle_normals[next.tri[0]] + obj.topology.triangle_normals[next.tri[1]];
                        EdgePair pair;
                        if (!edge_pair(a0, a1, v0, eo, glm::dot(eo, eo), bisector, reach, pair)) continue;
                        if (pair.behind < -rigid_back) continue;
                        if (replacing_count == kMaxReplacing) break;
                        Atom ee = a;
                        ee.object_edge = oe;
                        ee.sign = pair.sign;
                        replacing[replacing_count++] = ee;
                    }
                }
            } else if (!vertex_atoms(a.tool_vertex)) {
                return;
            }
            bool back = false;
            for (int k = 0; k < replacing_count; ++k)
                for (int g = 0; g < gone_count; ++g) back |= gone[g].same_as(replacing[k]);
            if (back) append(a);
            for (int k = 0; k < replacing_count; ++k) append(replacing[k]);
            if (gone_count < kMaxGone) gone[gone_count++] = a;
        }
        // Every contact real: taken with no more energy than the tolerance's give allows (the
        // swapped-in plane meets the slid-past answer to the tolerance, not exactly: the tool may
        // rise by a few tolerances). Still virtual: taken on for another round only with less.
        // An answer over the first allowance is given up before its guard.
        const double lift = 4.0 * tol, w_t = model.settings.haptic.weight_translational;
        EnergyLimit limit;
        limit.any = w.best_energy + 2.0 * std::sqrt(2.0 * w.best_energy * w_t) * lift + w_t * lift * lift;
        limit.virtual_answer = w.best_energy;
        ++stats.candidates;
        const CandidateResult cr = solve_candidate(model, base, frame, target, target_local, lower, upper, reach,
                                                   state.active, state.active_count, w, stats, limit);
        if (!cr.ok) return;
        const bool real = answer_is_real(model, w, tool_pose_at(base, cr.x));
        const double allowed = real ? limit.any : limit.virtual_answer;
        if (!(cr.energy <= allowed)) return;
        keep_candidate(model, cr, w, stats, x_sol);
        stats.atoms = w.best_count;
        ++stats.rescues;
        if (real) return;
    }
}

}  // namespace

StepResult step(const Model& model, State& state, const Pose& haptic_in) {
    const auto t_start = Clock::now();
    Workspace& w = workspace();
    const RendererSettings& S = model.settings;
    // The caller's word on this tick's work ahead of need, for this step only.
    const int defer = state.defer;
    state.defer = -1;
    StepResult res;
    w.tests = 0;
    w.detect_tests = 0;
    w.compliant_gathers = 0;
    w.bounds_measured = 0;
    w.quiet_triangles = 0;
    w.edge_queries = 0;
    w.edge_memos_ahead = 0;
    w.edge_due_count = 0;  // only this tick's gathers say which memos are due
    w.face_searches = 0;
    w.quiet_featured = 0;

    // Input health: a non-finite or non-unit pose is refused; the last pose is kept.
    const double qn = glm::length(haptic_in.orientation);
    if (!finite(haptic_in.position) || !finite(haptic_in.orientation) || std::abs(qn - 1.0) > 1e-3) {
        if (!state.initialized) state = make_state(Pose{});
        res.graphic = state.graphic;
        res.status = StepStatus::BadInput;
        compute_wrench(S.haptic, state.graphic, state.last_haptic, res.force_N, res.torque_Nm);
        return res;
    }
    Pose haptic = haptic_in;
    // Unit to rounding is kept as given, so that free motion reproduces the input bit for bit.
    if (std::abs(qn - 1.0) > 1e-12) haptic.orientation = haptic_in.orientation / qn;
    if (!state.initialized) state = make_state(haptic);
    // What the cache knows holds for this session at this tick only.
    NearCache& cache = w.cache;
    if (cache.session != state.session || cache.ticks != state.ticks || !same_pose(cache.graphic, state.graphic) ||
        !same_pose(cache.last_haptic, state.last_haptic)) {
        near_cache_reset(cache);
        for (Workspace::SatMemo& m : w.sat_memo) m.key = 0;
        for (auto& e : w.gap_extremes) e[0] = e[1] = 0;
        for (int& f : w.deep_rejecting) f = 0;
    }
    w.owner = (uint64_t(model.serial) << 32) ^ state.session;
    if (w.owner == 0) w.owner = ~uint64_t(0);
    // ---- detect ----
    const size_t nv = model.tool.mesh.vertices.size();
    if (nv > static_cast<size_t>(kMaxToolVertices) || model.tool.face_normals.size() > static_cast<size_t>(kMaxToolFaces) ||
        model.tool.edges.size() > static_cast<size_t>(kMaxToolEdges)) {
        res.graphic = state.graphic;
        res.status = StepStatus::Held;
        compute_wrench(S.haptic, state.graphic, haptic, res.force_N, res.torque_Nm);
        return res;
    }
    const Vec3 haptic_motion = haptic.position - state.last_haptic.position;
    const Vec3 haptic_rotation = quat_log(haptic.orientation * glm::conjugate(state.last_haptic.orientation));
    const double radius = std::max(model.tool.radius_m, 1e-6);
    Pose base = state.graphic;
    // The way the objects pushed the tool at the last tick (eq. 4's force direction).
    const Vec3 push = state.graphic.position - state.last_haptic.position;
    Vec3 moved(0.0);   // translation of earlier passes of this tick
    Vec3 turned(0.0);  // their rotation (sum of rotation vectors: a first-order account)
    w.soft = state.soft;

    double scale = 1.0;
    double xh[6], target[6], target_local[6], lower[6], upper[6];
    double reach = 0.0;
    bool solved = false;
    double x_sol[6] = {0, 0, 0, 0, 0, 0};
    bool free_motion = false;
    auto t_detect_end = t_start, t_gather_end = t_start;
    double stage_detect = 0, stage_gather = 0, stage_solve = 0;

    // The contact check of the solution (base, x_sol, the chosen atoms) as last made: made once
    // for the several questions asked of it, again once any of them changes.
    ContactCheck checked;
    bool checked_valid = false;
    auto contacts = [&]() -> const ContactCheck& {
        if (!checked_valid) checked = check_contacts(model, base, x_sol, w);
        checked_valid = true;
        return checked;
    };
    // A solution held on an extended plane (its contact is not real) becomes the base of another
    // pass of the stages within the tick, so the tool comes round the feature instead of hanging.
    bool have_prior = false;
    for (int pass = 0; pass < kMaxPasses; ++pass) {
        if (pass > 0 && w.near_complete && model.settings.near_cache) {
            // The last complete near set, detected at the earlier pass's base: the next pass
            // narrows it where it covers that pass's box.
            std::copy(w.near, w.near + w.near_count, w.prior);
            w.prior_count = w.near_count;
            w.prior_pose = base;
            std::copy(w.near_reach, w.near_reach + kMaxToolPieces, w.prior_reach);
            have_prior = true;
        }
        if (pass > 0) {
            const ToolPoseAt at = tool_pose_at(base, x_sol);
            moved += at.p - base.position;
            turned += Vec3(x_sol[3], x_sol[4], x_sol[5]);
            base.position = at.p;
            base.orientation = at.q;
            w.soft = best_soft_depths(w);
            solved = false;
            scale = 1.0;
        }
        // The haptic pose in step coordinates: translation and world rotation vector from the base.
        {
            const Vec3 dp = haptic.position - base.position;
            const Vec3 dt = quat_log(haptic.orientation * glm::conjugate(base.orientation));
            xh[0] = dp.x; xh[1] = dp.y; xh[2] = dp.z;
            xh[3] = dt.x; xh[4] = dt.y; xh[5] = dt.z;
        }
        place_tool_vertices(model.tool, base.orientation, base.position, w.tool_world);
        set_tool_planes(model, base.orientation, base.position, w);

        // The step's coordinates: eq. 5 as printed on the world axes; otherwise in the frame of
        // the tool at the last graphic pose, one frame for every pass of the tick (so the
        // per-axis boxes of successive passes bound the same total motion).
        const Mat3 frame = S.local_box == LocalBox::Paper ? Mat3(1.0) : glm::mat3_cast(state.graphic.orientation);
        const Vec3 motion_local = glm::transpose(frame) * haptic_motion;
        const Vec3 rotation_local = glm::transpose(frame) * haptic_rotation;
        const Vec3 moved_local = glm::transpose(frame) * moved;
        const Vec3 turned_local = glm::transpose(frame) * turned;
        for (int attempt = 0; attempt <= kMaxHalvings && !solved; ++attempt) {
            auto t0 = Clock::now();
            for (int j = 0; j < 6; ++j) target[j] = scale * xh[j];
            to_frame(frame, target, target_local);
            // The box of the step, and its force-continuity narrowing (used while in contact).
            double rate_lower[6], rate_upper[6];
            local_box(S, radius, target_local, motion_local, rotation_local, moved_local, turned_local, false, 0.0,
                      w.soft.spring_energy_J, lower, upper);
            local_box(S, radius, target_local, motion_local, rotation_local, moved_local, turned_local, true, 0.0,
                      w.soft.spring_energy_J, rate_lower, rate_upper);
            // Free motion (first pass only): the straight motion to the haptic pose, clear all
            // the way (CCD).
            if (pass == 0) {
                double straight_lo[6], straight_hi[6];
                for (int j = 0; j < 6; ++j) {
                    straight_lo[j] = std::min(0.0, target_local[j]);
                    straight_hi[j] = std::max(0.0, target_local[j]);
                }
                reach = box_reach(S, model.tool.radius_m, straight_lo, straight_hi);
                // In contact at the last tick, the tool moves freely only when nothing at all is
                // in reach of the path: the first triangle found settles it.
                if (!gather_near(model, base, w.tool_world, straight_lo, straight_hi, reach, w,
                                 state.active_count > 0)) {
                    scale *= 0.5;
                    stage_detect += micros(t0, Clock::now());
                    continue;
                }
                if (inside_box(target_local, lower, upper) &&
                    (w.near_count == 0 ||
                     (state.active_count == 0 && motion_is_free(model, base, target, S.contact_distance_m, w)))) {
                    res.stats.triangles_near = w.near_count;
                    free_motion = true;
                    solved = true;
                    for (int j = 0; j < 6; ++j) x_sol[j] = target[j];
                    stage_detect += micros(t0, Clock::now());
                    break;
                }
            }
            // In contact: what the force-continuity box can reach.
            reach = box_reach(S, model.tool.radius_m, rate_lower, rate_upper);
            const Mat3* prior_frame = have_prior ? &frame : nullptr;
            if (!gather_near(model, base, w.tool_world, rate_lower, rate_upper, reach, w, false, prior_frame)) {
                scale *= 0.5;
                stage_detect += micros(t0, Clock::now());
                continue;
            }
            res.stats.triangles_near = w.near_count;
            t_detect_end = Clock::now();
            stage_detect += micros(t0, t_detect_end);

            // ---- gather ----
            res.stats.gather_truncated |= !gather_atoms(model, base, rate_lower, rate_upper, push, w);
            t_gather_end = Clock::now();
            stage_gather += micros(t_detect_end, t_gather_end);
            res.stats.atoms_gathered = w.atom_count;

            // ---- solve, select ---- the force-continuity box first. A last pose inside the
            // tolerance (a graze) may need a step away from the haptic pose to come out: only
            // when nothing is feasible without it does every coordinate get that room, so it is
            // never spent on getting closer.
            for (int round = 0; round < 2 && !solved; ++round) {
                const double recover = round == 0 ? 0.0 : kRecoverTolerances * S.constraint_tol_m;
                local_box(S, radius, target_local, motion_local, rotation_local, moved_local, turned_local, true,
                          recover, w.soft.spring_energy_J, rate_lower, rate_upper);
                solved = solve_candidates(model, base, frame, target, target_local, rate_lower, rate_upper, reach, state,
                                          w, res.stats, x_sol);
            }
            // A tool the limit would leave touching nothing short of the haptic pose (a force at
            // a distance) is released: it goes as far as the step's box lets it, which reaches
            // further, so the triangles and atoms are gathered again. A contact held on an
            // extended plane is taken on by another pass instead.
            //
            // The released tool is first solved in the box of the straight motion to the target
            // (per coordinate between the start and the target): where no bound of that box holds
            // its answer, the answer stands in the step's box too (the same QP, with bounds that
            // hold nothing), and only what the straight box reaches is gathered. The step's box
            // reaches much further (the energy bound lets the tool turn far): lifting the probe
            // out of the tissue it brought in thousands of gingiva triangles.
            checked_valid = false;
            if (solved && S.rescue_virtual && contacts().any_virtual) {
                rescue_virtual(model, base, frame, target, target_local, rate_lower, rate_upper, reach, state, w,
                               res.stats, x_sol);
                checked_valid = false;
            }
            const ContactCheck cc = solved ? contacts() : ContactCheck{};
            bool at_target = solved;
            for (int j = 0; j < 6 && at_target; ++j) at_target = x_sol[j] == target[j];
            const bool released = solved && !cc.real && !cc.virtual_only && !at_target &&
                                  !within_contact_distance(model, w, tool_pose_at(base, x_sol));
            if (released) {
                res.stats.released = true;
                double straight_lo[6], straight_hi[6];
                for (int j = 0; j < 6; ++j) {
                    straight_lo[j] = std::max(lower[j], std::min(0.0, target_local[j]));
                    straight_hi[j] = std::min(upper[j], std::max(0.0, target_local[j]));
                }
                reach = box_reach(S, model.tool.radius_m, straight_lo, straight_hi);
                checked_valid = false;
                solved = gather_near(model, base, w.tool_world, straight_lo, straight_hi, reach, w, false, prior_frame);
                if (solved) {
                    res.stats.gather_truncated |= !gather_atoms(model, base, straight_lo, straight_hi, push, w);
                    solved = solve_candidates(model, base, frame, target, target_local, straight_lo, straight_hi, reach,
                                              state, w, res.stats, x_sol) &&
                             !w.best_box_held;
                }
            }
            if (released && !solved) {
                reach = box_reach(S, model.tool.radius_m, lower, upper);
                if (!gather_near(model, base, w.tool_world, lower, upper, reach, w, false, prior_frame)) {
                    solved = false;
                    scale *= 0.5;
                    continue;
                }
                res.stats.gather_truncated |= !gather_atoms(model, base, lower, upper, push, w);
                solved = false;
                for (int round = 0; round < 2 && !solved; ++round) {
                    const double recover = round == 0 ? 0.0 : kRecoverTolerances * S.constraint_tol_m;
                    local_box(S, radius, target_local, motion_local, rotation_local, moved_local, turned_local, false,
                              recover, w.soft.spring_energy_J, lower, upper);
                    solved = solve_candidates(model, base, frame, target, target_local, lower, upper, reach, state, w,
                                              res.stats, x_sol);
                }
            }
            stage_solve += micros(t_gather_end, Clock::now());
            if (!solved) scale *= 0.5;
        }
        if (!solved || free_motion || !contacts().any_virtual) break;
        ++res.stats.passes;
    }
    if (model.settings.near_cache) {
        // The superset in progress gets its slice where this tick has room for it.
        const auto t0 = Clock::now();
        // Work of this tick that came in a burst: the superset's slice and a tissue set's
        // gathering anew go to other ticks while they have room (the costs seldom meet).
        const bool burst = w.compliant_gathers > 0 || w.bounds_measured >= kHeavyBoundsMeasured ||
                           w.edge_queries >= kHeavyEdgeQueries || res.stats.relinearizations > 1 ||
                           res.stats.candidates > 2;
        // A tick that has already taken longer than defer_after_us (or that the caller says
        // to treat so) counts as heavy: the work waits while there is room.
        const bool deferred = defer >= 0 ? defer == 1 : micros(t_start, t0) > S.defer_after_us;
        res.stats.deferred = deferred;
        const Load load = res.stats.passes > 0 || res.stats.released                ? Load::Passes
                          : w.detect_tests >= kHeavyDetectTests || burst || deferred ? Load::Heavy
                          : w.tests <= kLightTests                                   ? Load::Light
                                                                                     : Load::Usual;
        const bool sliced = tend_superset(model, cache, load);
        if (model.any_compliant) tend_compliant_sets(model, w, sliced || burst || deferred);
        tend_edge_memos(model, w, sliced && load != Load::Light ? Load::Heavy : load);
        stage_detect += micros(t0, Clock::now());
    }
    bool base_stands = false;
    if (!solved && res.stats.passes > 0) {
        // A later pass found nothing better: its base, the earlier pass's answer, stands.
        solved = true;
        base_stands = true;
        for (double& v : x_sol) v = 0.0;
    }
    if (base_stands) checked_valid = false;
    if (solved && !free_motion && res.stats.passes > 0 && contacts().virtual_only) {
        // Still held only on extended planes after every pass: no safe answer this tick. The
        // last pose (a real contact) is kept rather than a force rendered at a distance.
        solved = false;
        base = state.graphic;
    }
    bool sliding = false;
    if (solved && !free_motion && model.any_friction && scale == 1.0) {
        const auto t0 = Clock::now();
        const Mat3 frame = S.local_box == LocalBox::Paper ? Mat3(1.0) : glm::mat3_cast(state.graphic.orientation);
        const Vec3 motion_local[4] = {glm::transpose(frame) * haptic_motion, glm::transpose(frame) * haptic_rotation,
                                      glm::transpose(frame) * moved, glm::transpose(frame) * turned};
        apply_friction(model, state, base, haptic, frame, motion_local, reach, x_sol, w, res.stats);
        sliding = res.stats.sliding;
        stage_solve += micros(t0, Clock::now());
    }

    const auto t_select = Clock::now();
    Pose graphic = base;
    state.active_count = 0;
    if (!solved) {
        res.status = StepStatus::Held;
    } else {
        const bool whole = scale == 1.0;
        if (free_motion && whole) {
            graphic = haptic;
        } else {
            const ToolPoseAt at = tool_pose_at(base, x_sol);
            graphic.position = at.p;
            graphic.orientation = at.q;
        }
        if (free_motion) {
            res.status = whole ? StepStatus::Free : StepStatus::Partial;
        } else {
            // The active contacts: atoms touching at the solution.
            const ToolPoseAt at = tool_pose_at(base, x_sol);
            for (int i = 0; i < w.best_count; ++i) {
                const double g = best_value(model, w, i, at);
                if (g <= S.contact_distance_m) {
                    const Atom& a = w.best[i];
                    if (a.kind == AtomKind::VertexFace) ++res.stats.active_vf;
                    else if (a.kind == AtomKind::FaceVertex) ++res.stats.active_fv;
                    else ++res.stats.active_ee;
                    if (state.active_count < kMaxActiveAtoms) state.active[state.active_count++] = a;
                }
            }
            res.contacts = res.stats.active_vf + res.stats.active_fv + res.stats.active_ee;
            set_tool_planes(model, graphic.orientation, graphic.position, w);
            double give = 0.0;
            for (int k = 0; k < w.best_slacks.zones; ++k) give = std::max(give, w.best_slacks.depth[k]);
            res.stats.soft_zones = w.best_slacks.zones;
            res.stats.soft_depth_m = give;
            res.stats.regions = count_regions(model, w, state.active, state.active_count, at, S.contact_distance_m, give);
            bool at_target = whole;
            for (int j = 0; j < 6 && at_target; ++j) at_target = x_sol[j] == xh[j];
            if (res.contacts == 0 && at_target) graphic = haptic;
            if (res.contacts > 0) res.status = StepStatus::Contact;
            else res.status = at_target ? StepStatus::Free : StepStatus::Partial;
        }
    }
    // The planes of compliant triangles that hold the tool at its answer go on to the next tick.
    state.held_plane_count = 0;
    if (S.carry_planes && solved && !free_motion) {
        const ToolPoseAt at = tool_pose_at(base, x_sol);
        for (int i = 0; i < w.best_count && state.held_plane_count < kMaxHeldPlanes; ++i) {
            if (w.best_key[i] == 0 || !model.objects[w.best[i].object].compliant ||
                best_value(model, w, i, at) > S.contact_distance_m)
                continue;
            uint64_t* end = state.held_planes + state.held_plane_count;
            if (std::find(state.held_planes, end, w.best_key[i]) == end)
                state.held_planes[state.held_plane_count++] = w.best_key[i];
        }
    }
    const auto t_force = Clock::now();
    state.graphic = graphic;
    state.last_haptic = haptic;
    // A held tick keeps the last pose, and with it how deep it is in a compliant zone.
    // The base (an earlier pass's answer) stands where the last pass found nothing better.
    if (solved) state.soft = res.contacts == 0 ? SoftDepths{} : base_stands ? w.soft : best_soft_depths(w);
    state.sliding = res.contacts > 0 && sliding;
    ++state.ticks;
    cache.session = state.session;
    cache.ticks = state.ticks;
    cache.graphic = state.graphic;
    cache.last_haptic = state.last_haptic;
    res.graphic = graphic;

    // ---- force ---- eq. 4
    compute_wrench(S.haptic, graphic, haptic, res.force_N, res.torque_Nm);
    const auto t_end = Clock::now();
    res.stats.times.detect_us = stage_detect;
    res.stats.times.gather_us = stage_gather;
    res.stats.times.solve_us = stage_solve;
    res.stats.times.select_us = micros(t_select, t_force);
    res.stats.times.force_us = micros(t_force, t_end);
    res.stats.triangles_tested = w.tests;
    res.stats.compliant_gathers = w.compliant_gathers;
    res.stats.quiet_triangles = w.quiet_triangles;
    res.stats.edge_queries = w.edge_queries;
    res.stats.edge_memos_ahead = w.edge_memos_ahead;
    res.stats.face_searches = w.face_searches;
    res.stats.quiet_featured = w.quiet_featured;
    return res;
}

}  // namespace sulcus
