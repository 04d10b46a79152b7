// Reading one triangle primitive of a glTF model (gltf_primitive.h).
#include "sulcus/engine/gltf_primitive.h"

#include <tiny_gltf.h>

#include <array>
#include <cstdint>
#include <cstring>
#include <numeric>
#include <vector>

namespace sulcus {

namespace {

// Locates element i of an accessor, with bounds checked against its buffer view and buffer.
struct AccessorView {
    const unsigned char* base = nullptr;
    size_t stride = 0;
    size_t count = 0;
};

bool view_accessor(const tinygltf::Model& model, int index, size_t element_size, AccessorView& view,
                   std::string& error) {
    const std::string name = "accessor " + std::to_string(index);
    if (index < 0 || size_t(index) >= model.accessors.size()) {
        error = name + " does not exist";
        return false;
    }
    const tinygltf::Accessor& acc = model.accessors[size_t(index)];
    if (acc.sparse.isSparse) {
        error = name + ": sparse accessors are not supported";
        return false;
    }
    if (acc.bufferView < 0 || size_t(acc.bufferView) >= model.bufferViews.size()) {
        error = name + ": no buffer view";
        return false;
    }
    const tinygltf::BufferView& bv = model.bufferViews[size_t(acc.bufferView)];
    if (bv.buffer < 0 || size_t(bv.buffer) >= model.buffers.size()) {
        error = name + ": buffer view without buffer";
        return false;
    }
    const tinygltf::Buffer& buf = model.buffers[size_t(bv.buffer)];
    const int stride = acc.ByteStride(bv);
    if (stride <= 0 || size_t(stride) < element_size) {
        error = name + ": bad byte stride";
        return false;
    }
    view.stride = size_t(stride);
    view.count = acc.count;
    if (view.count > bv.byteLength / view.stride + 1) {  // also keeps the sum below from overflowing
        error = name + ": count " + std::to_string(view.count) + " does not fit its buffer view";
        return false;
    }
    if (bv.byteOffset > buf.data.size() || bv.byteLength > buf.data.size() - bv.byteOffset) {
        error = name + ": buffer view runs past the end of its buffer";
        return false;
    }
    if (view.count > 0 && acc.byteOffset + (view.count - 1) * view.stride + element_size > bv.byteLength) {
        error = name + ": data runs past the end of its buffer view";
        return false;
    }
    view.base = buf.data.data() + bv.byteOffset + acc.byteOffset;
    return true;
}

const char* mode_name(int mode) {
    switch (mode) {
    case TINYGLTF_MODE_POINTS: return "points";
    case TINYGLTF_MODE_LINE: return "lines";
    case TINYGLTF_MODE_LINE_LOOP: return "line loop";
    case TINYGLTF_MODE_LINE_STRIP: return "line strip";
    case TINYGLTF_MODE_TRIANGLE_STRIP: return "triangle strip";
    case TINYGLTF_MODE_TRIANGLE_FAN: return "triangle fan";
    default: return "unknown";
    }
}

}  // namespace

bool append_gltf_triangles(const tinygltf::Model& model, const tinygltf::Primitive& prim, const glm::dmat4& transform,
                           TriMesh& out, std::string& error) {
    if (prim.mode != -1 && prim.mode != TINYGLTF_MODE_TRIANGLES) {
        error = "mode " + std::to_string(prim.mode) + " (" + mode_name(prim.mode) +
                ") is not supported: triangles only";
        return false;
    }
    const auto pos = prim.attributes.find("POSITION");
    if (pos == prim.attributes.end()) {
        error = "no POSITION attribute";
        return false;
    }
    AccessorView pv;
    if (!view_accessor(model, pos->second, 12, pv, error)) return false;
    const tinygltf::Accessor& pacc = model.accessors[size_t(pos->second)];
    if (pacc.type != TINYGLTF_TYPE_VEC3 || pacc.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT || pacc.normalized) {
        error = "POSITION must be VEC3 of FLOAT";
        return false;
    }
    const size_t first = out.vertices.size();
    if (pv.count > UINT32_MAX - first) {
        error = "too many vertices";
        return false;
    }
    for (size_t i = 0; i < pv.count; ++i) {
        float p[3];
        std::memcpy(p, pv.base + i * pv.stride, sizeof p);
        out.vertices.push_back(Vec3(transform * glm::dvec4(p[0], p[1], p[2], 1.0)));
    }

    std::vector<uint32_t> indices;
    if (prim.indices >= 0) {
        if (size_t(prim.indices) >= model.accessors.size()) {
            error = "indices accessor " + std::to_string(prim.indices) + " does not exist";
            return false;
        }
        const tinygltf::Accessor& iacc = model.accessors[size_t(prim.indices)];
        size_t size = 0;
        switch (iacc.componentType) {
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: size = 1; break;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: size = 2; break;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: size = 4; break;
        default: error = "indices must be unsigned byte, short or int"; return false;
        }
        if (iacc.type != TINYGLTF_TYPE_SCALAR) {
            error = "indices must be SCALAR";
            return false;
        }
        AccessorView iv;
        if (!view_accessor(model, prim.indices, size, iv, error)) return false;
        indices.resize(iv.count);
        for (size_t i = 0; i < iv.count; ++i) {
            const unsigned char* p = iv.base + i * iv.stride;
            if (size == 1) {
                indices[i] = p[0];
            } else if (size == 2) {
                uint16_t v;
                std::memcpy(&v, p, 2);
                indices[i] = v;
            } else {
                std::memcpy(&indices[i], p, 4);
            }
            if (indices[i] >= pv.count) {
                error = "index " + std::to_string(indices[i]) + " out of range (" + std::to_string(pv.count) +
                        " vertices)";
                return false;
            }
        }
    } else {
        indices.resize(pv.count);
        std::iota(indices.begin(), indices.end(), 0u);
    }
    if (indices.size() % 3 != 0) {
        error = "index count " + std::to_string(indices.size()) + " is not a multiple of 3";
        return false;
    }
    const bool mirrored = glm::determinant(glm::dmat3(transform)) < 0.0;
    out.triangles.reserve(out.triangles.size() + indices.size() / 3);
    for (size_t i = 0; i < indices.size(); i += 3) {
        const uint32_t a = uint32_t(first) + indices[i], b = uint32_t(first) + indices[i + 1],
                       c = uint32_t(first) + indices[i + 2];
        out.triangles.push_back(mirrored ? std::array<uint32_t, 3>{a, c, b} : std::array<uint32_t, 3>{a, b, c});
    }
    return true;
}

}  // namespace sulcus
