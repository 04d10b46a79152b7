// Time of the BVH and the proximity queries on a dense mesh: a UV sphere of radius 10 mm with
// about 200k triangles (edges about 0.1 mm), and a Williams probe as the tool.
//
//   bench_bvh [google benchmark flags]      e.g. --benchmark_min_time=0.05 for a quick run
//
// Counters: tris/query (triangles reported by a box query, or reaching an exact test in a
// proximity query), nodes/query (BVH nodes visited), hits (fraction of collision queries that
// found an overlap).
#include "sulcus/content/probes.h"
#include "sulcus/engine/bvh.h"
#include "sulcus/engine/proximity.h"
#include "sulcus/engine/renderer.h"

#include <benchmark/benchmark.h>

#include <cmath>
#include <memory>
#include <random>
#include <vector>

namespace {

using namespace sulcus;

constexpr double kRadius = 10e-3;
constexpr int kPool = 256;  // distinct queries cycled through

// UV sphere: `rings` latitude bands of `segments` quads (fans at the poles), outward.
TriMesh uv_sphere(int rings, int segments, double radius) {
    TriMesh m;
    m.vertices.push_back({0.0, radius, 0.0});
    for (int r = 1; r < rings; ++r) {
        const double th = M_PI * r / rings;
        for (int s = 0; s < segments; ++s) {
            const double ph = 2.0 * M_PI * s / segments;
            m.vertices.push_back(radius * Vec3(std::sin(th) * std::cos(ph), std::cos(th), std::sin(th) * std::sin(ph)));
        }
    }
    m.vertices.push_back({0.0, -radius, 0.0});
    const uint32_t south = uint32_t(m.vertices.size() - 1);
    auto at = [&](int r, int s) { return uint32_t(1 + (r - 1) * segments + (s % segments)); };
    for (int s = 0; s < segments; ++s) m.triangles.push_back({0, at(1, s + 1), at(1, s)});
    for (int r = 1; r < rings - 1; ++r)
        for (int s = 0; s < segments; ++s) {
            m.triangles.push_back({at(r, s), at(r, s + 1), at(r + 1, s + 1)});
            m.triangles.push_back({at(r, s), at(r + 1, s + 1), at(r + 1, s)});
        }
    for (int s = 0; s < segments; ++s) m.triangles.push_back({south, at(rings - 1, s), at(rings - 1, s + 1)});
    return m;
}

const TriMesh& sphere() {
    static const TriMesh m = uv_sphere(317, 316, kRadius);  // 199,712 triangles
    return m;
}

Vec3 random_direction(std::mt19937_64& g) {
    std::normal_distribution<double> n(0.0, 1.0);
    return glm::normalize(Vec3(n(g), n(g), n(g)));
}

// The probe model over the sphere, built once for all the proximity benchmarks.
const Model& probe_model() {
    static const std::unique_ptr<Model> model = [] {
        SceneObject o;
        o.name = "sphere";
        o.mesh = sphere();
        ModelBuild b = build_model(make_probe_collision(ProbeKind::Williams), {o}, RendererSettings{});
        if (!b.model) std::abort();
        return std::move(b.model);
    }();
    return *model;
}

// Probe poses with the tip end `lo`..`hi` metres outside the sphere's surface and the probe
// (+Y toward the handle) pointing away from it, tilted up to 60 degrees.
std::vector<Pose> near_poses(double lo, double hi, uint64_t seed) {
    std::mt19937_64 g(seed);
    std::uniform_real_distribution<double> off(lo, hi), tilt(0.0, M_PI / 3.0), spin(0.0, 2.0 * M_PI);
    std::vector<Pose> poses;
    for (int i = 0; i < kPool; ++i) {
        const Vec3 n = random_direction(g);
        const Quat to_normal(Vec3(0, 1, 0), n);  // shortest arc from +Y to n
        const Quat q = glm::angleAxis(tilt(g), glm::normalize(glm::cross(n, random_direction(g)))) * to_normal *
                       glm::angleAxis(spin(g), Vec3(0, 1, 0));
        poses.push_back(Pose{(kRadius + off(g)) * n, glm::normalize(q)});
    }
    return poses;
}

void BM_BvhBuild(benchmark::State& state) {
    const TriMesh& m = sphere();
    for (auto _ : state) {
        Bvh bvh(m);
        benchmark::DoNotOptimize(bvh.nodes().data());
    }
    state.counters["triangles"] = double(m.triangles.size());
    state.SetItemsProcessed(state.iterations() * int64_t(m.triangles.size()));
}
BENCHMARK(BM_BvhBuild)->Unit(benchmark::kMillisecond);

// Boxes of the given edge (micrometres) centred on the surface.
void BM_BvhQuery(benchmark::State& state) {
    static const Bvh bvh(sphere());
    const double edge = double(state.range(0)) * 1e-6;
    std::mt19937_64 g(7);
    std::vector<Aabb> boxes;
    for (int i = 0; i < kPool; ++i) {
        Aabb b;
        b.grow(kRadius * random_direction(g));
        b.inflate(0.5 * edge);
        boxes.push_back(b);
    }
    size_t n = 0;
    long found = 0, queries = 0;
    for (auto _ : state) {
        long k = 0;
        bvh.query(boxes[n], [&k](uint32_t) {
            ++k;
            return true;
        });
        benchmark::DoNotOptimize(k);
        found += k;
        ++queries;
        n = (n + 1) % boxes.size();
    }
    state.counters["tris/query"] = double(found) / double(queries);
}
BENCHMARK(BM_BvhQuery)->ArgName("edge_um")->Arg(1000)->Arg(5000);

// Exact distance with the tip 0.05-0.5 mm off the surface; max distance 1 mm, or 10 mm
// (Arg: max distance in micrometres).
void BM_ToolDistance(benchmark::State& state) {
    const Model& model = probe_model();
    static const std::vector<Pose> poses = near_poses(0.05e-3, 0.5e-3, 11);
    const double cap = double(state.range(0)) * 1e-6;
    size_t n = 0;
    long tris = 0, nodes = 0, queries = 0;
    for (auto _ : state) {
        ProximityStats st;
        benchmark::DoNotOptimize(tool_distance(model, poses[n], cap, &st));
        tris += st.triangles_tested;
        nodes += st.nodes_visited;
        ++queries;
        n = (n + 1) % poses.size();
    }
    state.counters["tris/query"] = double(tris) / double(queries);
    state.counters["nodes/query"] = double(nodes) / double(queries);
}
BENCHMARK(BM_ToolDistance)->ArgName("max_um")->Arg(1000)->Arg(10000);

// Overlap with the tip from 0.2 mm inside to 0.2 mm outside the surface (about half hit).
void BM_ToolCollides(benchmark::State& state) {
    const Model& model = probe_model();
    static const std::vector<Pose> poses = near_poses(-0.2e-3, 0.2e-3, 13);
    size_t n = 0;
    long tris = 0, nodes = 0, hits = 0, queries = 0;
    for (auto _ : state) {
        ProximityStats st;
        const bool hit = tool_collides(model, poses[n], &st);
        benchmark::DoNotOptimize(hit);
        hits += hit;
        tris += st.triangles_tested;
        nodes += st.nodes_visited;
        ++queries;
        n = (n + 1) % poses.size();
    }
    state.counters["tris/query"] = double(tris) / double(queries);
    state.counters["nodes/query"] = double(nodes) / double(queries);
    state.counters["hits"] = double(hits) / double(queries);
}
BENCHMARK(BM_ToolCollides);

}  // namespace

BENCHMARK_MAIN();
