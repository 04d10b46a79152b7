// Side-by-side timing of our proximity queries (sulcus/engine/proximity.h) against FCL, the
// Flexible Collision Library (Debian libfcl-dev), on the same meshes and tool poses. Built with
// FCL only when the build found it (SULCUS_HAVE_FCL); otherwise it reports that it is missing.
#pragma once

#include "sulcus/engine/renderer.h"
#include "sulcus/engine/runner.h"
#include "sulcus/engine/types.h"

#include <string>
#include <vector>

namespace sulcus::cli {

// One kind of query ("distance" or "collision") timed over the poses.
struct PeerQueryTiming {
    std::string query;
    long queries = 0;                  // poses timed (each query repeated, see compare_with_fcl)
    Percentiles ours_us, peer_us;      // time of one query in microseconds, over the poses
    double ratio = 0.0;                // peer median over ours median: > 1 means ours is faster
    double max_difference_m = 0.0;     // distance: largest |ours - FCL| where both say apart
    long disagreements = 0;            // poses where the two disagree on contact beyond a touch:
                                       // distance: one says apart by more than 1 nm, the other not,
                                       // and they differ by more than 1 nm; collision: the verdicts
                                       // differ where both distances say apart by more than 1 nm
};

struct PeerComparison {
    std::string error;  // empty when the comparison ran
    std::vector<PeerQueryTiming> queries;
};

// Whether this build carries FCL.
bool fcl_available();

// Times our tool_distance / tool_collides against FCL's distance / collide on the same meshes
// (the model's tool mesh in the tool frame and each object's world mesh, as
// fcl::BVHModel<fcl::OBBRSSd>, built once and not timed) at the same poses. Each query is
// repeated at its pose until the repetitions take at least 2 us, and the time of one query is
// their mean; the percentiles are over the poses. FCL's side of a query is setting the tool's
// transform and one fcl::distance (fcl::collide) call per object, keeping the least distance
// (stopping at the first collision), as ours stops at the first overlap. Distance is exact on
// both sides (no cap: ours is called with an infinite max_distance_m) and compared only where
// both say the tool is apart from every object.
PeerComparison compare_with_fcl(const Model& model, const std::vector<Pose>& poses);

}  // namespace sulcus::cli
