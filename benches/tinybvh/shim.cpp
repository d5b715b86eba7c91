// A C interface to tinybvh's BVH8_CPU (8-wide, AVX2 + FMA traversal) for
// glint's benchmark anchors: build over a triangle soup, closest hit,
// occlusion, and the size of what traversal reads. Compiled by build.rs with
// -O3 -mavx2 -mfma only when the host CPU and the compiler allow it.
#define TINYBVH_IMPLEMENTATION
#include "tiny_bvh.h"

#include <cmath>
#include <cstdint>

using namespace tinybvh;

extern "C" {

// Builds over `tri_count` triangles, three xyzw vertices each (`verts` must
// outlive the BVH: tinybvh keeps the binary BVH it converts from, which
// points at them).
void* glint_tbvh8_build(const float* verts, uint32_t tri_count) {
    BVH8_CPU* bvh = new BVH8_CPU();
    bvh->Build(reinterpret_cast<const bvhvec4*>(verts), tri_count);
    return bvh;
}

void glint_tbvh8_free(void* bvh) { delete static_cast<BVH8_CPU*>(bvh); }

// Bytes of interleaved node and triangle blocks that traversal reads: the
// blocks are 64-byte cache lines (ConvertFrom allocates usedBlocks * 64; the
// header's "16-byte blocks" comment is stale).
uint64_t glint_tbvh8_bytes(const void* bvh) {
    return uint64_t(static_cast<const BVH8_CPU*>(bvh)->usedBlocks) * 64;
}

// Closest hit along origin + t dir, t in (0, inf): the ray parameter t (in
// units of |dir|, as glint's) and the triangle, or 0 for a miss. tinybvh
// normalises the direction, so its distance is divided by |dir|.
int glint_tbvh8_intersect(const void* bvh, const float* o, const float* d, float* t,
                          uint32_t* prim) {
    Ray ray(bvhvec3(o[0], o[1], o[2]), bvhvec3(d[0], d[1], d[2]));
    static_cast<const BVH8_CPU*>(bvh)->Intersect(ray);
    if (ray.hit.t >= BVH_FAR) return 0;
    *t = ray.hit.t / std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    *prim = ray.hit.prim;
    return 1;
}

// Whether anything blocks origin + t dir for t in (0, t_max).
int glint_tbvh8_occluded(const void* bvh, const float* o, const float* d, float t_max) {
    const float len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    Ray ray(bvhvec3(o[0], o[1], o[2]), bvhvec3(d[0], d[1], d[2]), t_max * len);
    return static_cast<const BVH8_CPU*>(bvh)->IsOccluded(ray) ? 1 : 0;
}

}  // extern "C"
