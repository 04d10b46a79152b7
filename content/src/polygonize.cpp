// Marching tetrahedra over a sparse set of grid blocks, and decimation through OpenMesh.
//
// The grid is split into blocks of kBlock^3 cells. A block is evaluated in full when its coarse
// corner values say the surface may pass through it; then any block that shares a face carrying a
// sign change with an evaluated block is evaluated too, until no evaluated block has a crossing on
// a face toward an unevaluated one. So the surface is never cut at a block boundary: the output is
// as closed as a full-grid evaluation, at a cost that grows with the area instead of the volume.
// Decimation is in decimate.cpp.
#include "sulcus/content/polygonize.h"


#include <algorithm>
#include <cmath>
#include <deque>
#include <stdexcept>
#include <unordered_map>

namespace sulcus {

double smooth_min(double a, double b, double k) {
    if (k <= 0.0) return std::min(a, b);
    // Polynomial smooth minimum: equal to min(a, b) when |a - b| >= k, rounded within.
    const double h = std::clamp(0.5 + 0.5 * (b - a) / k, 0.0, 1.0);
    return b + (a - b) * h - k * h * (1.0 - h);
}

double smooth_max(double a, double b, double k) { return -smooth_min(-a, -b, k); }

namespace {

constexpr int kBlock = 8;
// Vertices are kept this fraction of an edge away from its grid points, so no triangle collapses
// to a point; the surface moves by at most this fraction of a cell.
constexpr double kEdgeClamp = 0.01;

struct Grid {
    Vec3 origin;
    double h = 0.0;
    int64_t n[3]{};   // grid points per axis
    int64_t nb[3]{};  // blocks per axis
    Vec3 point(int64_t i, int64_t j, int64_t k) const {
        return origin + Vec3(double(i) * h, double(j) * h, double(k) * h);
    }
    int64_t index(int64_t i, int64_t j, int64_t k) const { return i + n[0] * (j + n[1] * k); }
};

// A grid value, never exactly zero (zero counts as outside).
double sample(const ImplicitField& f, const Vec3& p) {
    const double v = f(p);
    if (!std::isfinite(v)) throw std::invalid_argument("polygonize: the field is not finite at a grid point");
    return v == 0.0 ? std::numeric_limits<double>::min() : v;
}

struct Block {
    int64_t bi, bj, bk;
    std::vector<double> v;  // (kBlock+1)^3 values
    double at(int i, int j, int k) const { return v[size_t(i + (kBlock + 1) * (j + (kBlock + 1) * k))]; }
};

// The six tetrahedra of the Kuhn split of a cube (corner c = x + 2y + 4z), all sharing the diagonal
// 0-7, positively oriented.
struct TetTable {
    int t[6][4];
    TetTable() {
        const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
        for (int p = 0; p < 6; ++p) {
            const int a = 1 << perms[p][0], b = 1 << perms[p][1];
            int tet[4] = {0, a, a | b, 7};
            // Orientation = parity of the axis permutation; make every tetrahedron positive.
            const bool odd = (p == 1 || p == 2 || p == 5);
            if (odd) std::swap(tet[2], tet[3]);
            for (int q = 0; q < 4; ++q) t[p][q] = tet[q];
        }
    }
};

bool odd_permutation(const int (&p)[4]) {
    int inv = 0;
    for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j) inv += p[i] > p[j];
    return inv & 1;
}

class Extractor {
public:
    Extractor(const ImplicitField& f, const Grid& g, int refine) : f_(f), g_(g), refine_(refine) {}

    // Vertex on the grid edge between points a and b (global indices) with values va, vb of
    // opposite sign.
    uint32_t vertex(int64_t a, const Vec3& pa, double va, int64_t b, const Vec3& pb, double vb) {
        if (a > b) {
            std::swap(a, b);
            std::swap(va, vb);
            return vertex_sorted(a, pb, va, b, pa, vb);
        }
        return vertex_sorted(a, pa, va, b, pb, vb);
    }

    TriMesh mesh;

private:
    uint32_t vertex_sorted(int64_t a, const Vec3& pa, double va, int64_t b, const Vec3& pb, double vb) {
        auto [it, fresh] = map_.try_emplace(std::make_pair(a, b), 0u);
        if (!fresh) return it->second;
        // Regula falsi (Illinois) on the segment, starting from the linear interpolation.
        double ta = 0.0, tb = 1.0, fa = va, fb = vb;
        double t = fa / (fa - fb);
        for (int it2 = 0; it2 < refine_; ++it2) {
            const double ft = f_(pa + (pb - pa) * t);
            if (!std::isfinite(ft) || std::abs(ft) < 1e-6 * g_.h) break;
            if ((ft < 0.0) == (fa < 0.0)) {
                ta = t;
                fa = ft;
                fb *= 0.5;
            } else {
                tb = t;
                fb = ft;
                fa *= 0.5;
            }
            if (tb - ta < 1e-7) break;
            t = ta + (tb - ta) * fa / (fa - fb);
        }
        t = std::clamp(t, kEdgeClamp, 1.0 - kEdgeClamp);
        mesh.vertices.push_back(pa + (pb - pa) * t);
        it->second = uint32_t(mesh.vertices.size() - 1);
        return it->second;
    }

    struct PairHash {
        size_t operator()(const std::pair<int64_t, int64_t>& p) const {
            return std::hash<int64_t>()(p.first * 0x9E3779B97F4A7C15LL ^ p.second);
        }
    };
    const ImplicitField& f_;
    const Grid& g_;
    int refine_;
    std::unordered_map<std::pair<int64_t, int64_t>, uint32_t, PairHash> map_;
};

}  // namespace

TriMesh polygonize(const ImplicitField& field, const Aabb& box, const PolygonizeSettings& settings) {
    if (!(settings.cell_m > 0.0) || settings.refine_steps < 0)
        throw std::invalid_argument("polygonize: cell size must be positive");
    const Vec3 ext = box.hi - box.lo;
    if (!(ext.x > 0.0 && ext.y > 0.0 && ext.z > 0.0)) throw std::invalid_argument("polygonize: empty box");
    Grid g;
    g.h = settings.cell_m;
    for (int a = 0; a < 3; ++a) {
        const int64_t cells = int64_t(std::ceil(ext[a] / g.h));
        g.nb[a] = (cells + kBlock - 1) / kBlock;
        g.n[a] = g.nb[a] * kBlock + 1;
        if (g.n[a] > (int64_t(1) << 20)) throw std::invalid_argument("polygonize: grid too large");
    }
    // Centre the grid on the box.
    for (int a = 0; a < 3; ++a) g.origin[a] = box.lo[a] - 0.5 * (double(g.n[a] - 1) * g.h - ext[a]);

    // Coarse values at block corners.
    const int64_t cn[3] = {g.nb[0] + 1, g.nb[1] + 1, g.nb[2] + 1};
    std::vector<double> coarse(size_t(cn[0] * cn[1] * cn[2]));
    auto cidx = [&](int64_t i, int64_t j, int64_t k) { return size_t(i + cn[0] * (j + cn[1] * k)); };
    for (int64_t k = 0; k < cn[2]; ++k)
        for (int64_t j = 0; j < cn[1]; ++j)
            for (int64_t i = 0; i < cn[0]; ++i) {
                const double v = sample(field, g.point(i * kBlock, j * kBlock, k * kBlock));
                const bool boundary = i == 0 || j == 0 || k == 0 || i == cn[0] - 1 || j == cn[1] - 1 || k == cn[2] - 1;
                if (boundary && v < 0.0)
                    throw std::invalid_argument("polygonize: the solid reaches the edge of the box");
                coarse[cidx(i, j, k)] = v;
            }

    // Candidate blocks: a corner near the surface (within twice the block diagonal, allowing for a
    // field that overstates distance by up to 2) or corners of both signs.
    const double reach = 2.0 * std::sqrt(3.0) * kBlock * g.h;
    const int64_t nblocks = g.nb[0] * g.nb[1] * g.nb[2];
    std::vector<int32_t> slot(size_t(nblocks), -1);
    std::vector<Block> blocks;
    std::deque<int64_t> queue;
    auto bidx = [&](int64_t i, int64_t j, int64_t k) { return i + g.nb[0] * (j + g.nb[1] * k); };
    auto activate = [&](int64_t i, int64_t j, int64_t k) {
        if (i < 0 || j < 0 || k < 0 || i >= g.nb[0] || j >= g.nb[1] || k >= g.nb[2]) return;
        const int64_t b = bidx(i, j, k);
        if (slot[size_t(b)] >= 0) return;
        slot[size_t(b)] = int32_t(blocks.size());
        Block blk{i, j, k, {}};
        blk.v.resize(size_t((kBlock + 1) * (kBlock + 1) * (kBlock + 1)));
        for (int z = 0; z <= kBlock; ++z)
            for (int y = 0; y <= kBlock; ++y)
                for (int x = 0; x <= kBlock; ++x)
                    blk.v[size_t(x + (kBlock + 1) * (y + (kBlock + 1) * z))] =
                        sample(field, g.point(i * kBlock + x, j * kBlock + y, k * kBlock + z));
        blocks.push_back(std::move(blk));
        queue.push_back(b);
    };
    for (int64_t k = 0; k < g.nb[2]; ++k)
        for (int64_t j = 0; j < g.nb[1]; ++j)
            for (int64_t i = 0; i < g.nb[0]; ++i) {
                bool neg = false, pos = false, near = false;
                for (int c = 0; c < 8; ++c) {
                    const double v = coarse[cidx(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1))];
                    neg |= v < 0.0;
                    pos |= v > 0.0;
                    near |= std::abs(v) < reach;
                }
                if (near || (neg && pos)) activate(i, j, k);
            }
    // Close the set: a face of an evaluated block with both signs on it needs its neighbour.
    while (!queue.empty()) {
        const int64_t b = queue.front();
        queue.pop_front();
        const Block blk = blocks[size_t(slot[size_t(b)])];  // copy: activate() may reallocate
        for (int axis = 0; axis < 3; ++axis)
            for (int side = 0; side < 2; ++side) {
                bool neg = false, pos = false;
                for (int u = 0; u <= kBlock; ++u)
                    for (int w = 0; w <= kBlock; ++w) {
                        int c[3];
                        c[axis] = side * kBlock;
                        c[(axis + 1) % 3] = u;
                        c[(axis + 2) % 3] = w;
                        const double v = blk.at(c[0], c[1], c[2]);
                        neg |= v < 0.0;
                        pos |= v > 0.0;
                    }
                if (!(neg && pos)) continue;
                int64_t nbk[3] = {blk.bi, blk.bj, blk.bk};
                nbk[axis] += side ? 1 : -1;
                if (nbk[axis] < 0 || nbk[axis] >= g.nb[axis])
                    throw std::invalid_argument("polygonize: the solid reaches the edge of the box");
                activate(nbk[0], nbk[1], nbk[2]);
            }
    }

    // Extract in block-index order so the output does not depend on the discovery order.
    std::vector<int64_t> order;
    order.reserve(blocks.size());
    for (int64_t b = 0; b < nblocks; ++b)
        if (slot[size_t(b)] >= 0) order.push_back(b);

    static const TetTable tets;
    Extractor ex(field, g, settings.refine_steps);
    for (int64_t b : order) {
        const Block& blk = blocks[size_t(slot[size_t(b)])];
        for (int z = 0; z < kBlock; ++z)
            for (int y = 0; y < kBlock; ++y)
                for (int x = 0; x < kBlock; ++x) {
                    double cv[8];
                    int inside = 0;
                    for (int c = 0; c < 8; ++c) {
                        cv[c] = blk.at(x + (c & 1), y + ((c >> 1) & 1), z + ((c >> 2) & 1));
                        inside += cv[c] < 0.0;
                    }
                    if (inside == 0 || inside == 8) continue;
                    int64_t gi[8];
                    Vec3 gp[8];
                    for (int c = 0; c < 8; ++c) {
                        const int64_t i = blk.bi * kBlock + x + (c & 1), j = blk.bj * kBlock + y + ((c >> 1) & 1),
                                      k = blk.bk * kBlock + z + ((c >> 2) & 1);
                        gi[c] = g.index(i, j, k);
                        gp[c] = g.point(i, j, k);
                    }
                    auto vert = [&](int p, int q) { return ex.vertex(gi[p], gp[p], cv[p], gi[q], gp[q], cv[q]); };
                    for (const auto& t : tets.t) {
                        int in[4], out[4], ni = 0, no = 0;
                        for (int q = 0; q < 4; ++q) (cv[t[q]] < 0.0 ? in[ni++] : out[no++]) = t[q];
                        if (ni == 0 || ni == 4) continue;
                        // Reorder (in..., out...) into an even permutation of the positive tetrahedron.
                        int perm[4], loc[4];
                        for (int q = 0; q < ni; ++q) perm[q] = in[q];
                        for (int q = 0; q < no; ++q) perm[ni + q] = out[q];
                        for (int q = 0; q < 4; ++q)
                            for (int r = 0; r < 4; ++r)
                                if (t[r] == perm[q]) loc[q] = r;
                        if (odd_permutation(loc)) {
                            // Swap two vertices of the same group so the split stays the same.
                            if (ni >= 2) std::swap(perm[0], perm[1]);
                            else std::swap(perm[2], perm[3]);
                        }
                        auto& tris = ex.mesh.triangles;
                        if (ni == 1) {
                            const int a = perm[0], b2 = perm[1], c2 = perm[2], d = perm[3];
                            tris.push_back({vert(a, b2), vert(a, c2), vert(a, d)});
                        } else if (ni == 3) {
                            const int d = perm[3], a = perm[0], b2 = perm[1], c2 = perm[2];
                            // One outside vertex d; (a, b, c, d) even: the face opposite d seen
                            // from d is (a, c, b); the normal points toward d.
                            tris.push_back({vert(a, d), vert(b2, d), vert(c2, d)});
                        } else {
                            const int a = perm[0], b2 = perm[1], c2 = perm[2], d = perm[3];
                            const uint32_t pac = vert(a, c2), pad = vert(a, d), pbd = vert(b2, d), pbc = vert(b2, c2);
                            const auto& V = ex.mesh.vertices;
                            if (glm::length(V[pac] - V[pbd]) <= glm::length(V[pad] - V[pbc])) {
                                tris.push_back({pac, pad, pbd});
                                tris.push_back({pac, pbd, pbc});
                            } else {
                                tris.push_back({pac, pad, pbc});
                                tris.push_back({pad, pbd, pbc});
                            }
                        }
                    }
                }
    }
    return std::move(ex.mesh);
}

}  // namespace sulcus
