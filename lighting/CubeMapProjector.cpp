// CubeMapProjector.cpp — exact-solid-angle cube-map projection (see CubeMapProjector.h).
//
// [SECTION] Table-path kernels (AVX2 + FMA chosen at run time, baseline otherwise)
// [SECTION] Folded projection (mirror symmetry of a face, N a multiple of 16)
// [SECTION] Texel solid angles
// [SECTION] Basis textures (per-N tables, shared)
// [SECTION] Projection of one face: table path, streaming path
// [SECTION] Sums and whole-map projection
#include "lighting/CubeMapProjector.h"

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <mutex>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "lighting/SunTexel.h"
#include "world/Error.h"

namespace amb {

namespace {

// Rec. 709 luminance (world/Conventions.h), used only to find sun texels.
double luminance(double r, double g, double b) {
    return amb::luminance(glm::dvec3(r, g, b));
}

// Signed area term of the texel solid-angle formula: the solid angle of the face rectangle
// [0, x] x [0, y] at unit distance is atan2(x y, sqrt(x^2 + y^2 + 1)).
double areaTerm(double x, double y) {
    return std::atan2(x * y, std::sqrt(x * x + y * y + 1.0));
}

double faceCoordinate(int a, int n) {
    return 2.0 * a / n - 1.0;
}

// A texel channel value is usable when it is finite and non-negative (NaN fails both compares).
inline bool usable(float x) {
    return x >= 0.0f && x <= FLT_MAX;
}

// ---- Table-path kernels ---------------------------------------------------------------------
//
// Two passes per face. (1) De-interleave the RGB face into three float planes and check in the
// same pass that every value is finite, >= 0 and not above the sun threshold (luminance <= the
// largest channel, so then no texel can be a sun texel). (2) For each coefficient, a dot product
// of its basis texture with each plane. Coefficients are taken three at a time so that 9
// accumulators, 3 planes and a weight fit in 16 vector registers; each float lane sums at most
// kChunkBlocks products before it is flushed into double. Both passes exist as AVX2 + FMA code,
// chosen at run time when the CPU has it (the project's compile flags stay at the baseline ISA),
// and as plain loops for any other CPU.

constexpr int kLanes = 8;         // texels per block
constexpr int kChunkBlocks = 32;  // products per float lane before the flush into double

int paddedTexels(int n) {
    return (n * n + kLanes - 1) / kLanes * kLanes;
}

using Sums = double[kShCoefficients][3];

bool deinterleaveBaseline(const float* rgb, int m, float limit, float* r, float* g, float* b) {
    bool ok = true;
    for (int t = 0; t < m; ++t) {
        const float R = rgb[3 * t], G = rgb[3 * t + 1], B = rgb[3 * t + 2];
        ok &= (R >= 0.0f) & (R <= limit) & (G >= 0.0f) & (G <= limit) & (B >= 0.0f) & (B <= limit);
        r[t] = R;
        g[t] = G;
        b[t] = B;
    }
    return ok;
}

void multiplyAddBaseline(const float* weights, int padded, const float* const planes[3], Sums out) {
    for (int k = 0; k < kShCoefficients; ++k) {
        const float* w = weights + std::size_t(k) * padded;
        for (int c = 0; c < 3; ++c) {
            const float* d = planes[c];
            double total = 0.0;
            for (int c0 = 0; c0 < padded; c0 += kChunkBlocks * kLanes) {
                const int end = std::min(padded, c0 + kChunkBlocks * kLanes);
                float acc[kLanes] = {};
                for (int t = c0; t < end; t += kLanes)
                    for (int l = 0; l < kLanes; ++l) acc[l] += w[t + l] * d[t + l];
                for (int l = 0; l < kLanes; ++l) total += acc[l];
            }
            out[k][c] = total;
        }
    }
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define AMB_PROJECTOR_AVX2 1

// 8 texels = 24 floats in a0 (r0 g0 b0 r1 g1 b1 r2 g2), a1 (b2 r3 g3 b3 r4 g4 b4 r5), a2 (g5 b5
// r6 g6 b6 r7 g7 b7): two blends gather one channel, a permutation puts it in texel order. The
// check uses the bit patterns: a float is in [+0, limit] exactly when its bits, read as an
// unsigned integer, are <= those of limit (negative values have the sign bit set, NaN and Inf
// lie above every finite value), so one unsigned max per vector suffices. -0.0 fails it and
// takes the exact path, which accepts it.
__attribute__((target("avx2,fma"))) bool deinterleaveAvx2(const float* rgb, int m, float limit,
                                                          float* r, float* g, float* b) {
    __m256i highest = _mm256_setzero_si256();
    const __m256i orderR = _mm256_setr_epi32(0, 3, 6, 1, 4, 7, 2, 5);
    const __m256i orderG = _mm256_setr_epi32(1, 4, 7, 2, 5, 0, 3, 6);
    const __m256i orderB = _mm256_setr_epi32(2, 5, 0, 3, 6, 1, 4, 7);
    int t = 0;
    for (; t + kLanes <= m; t += kLanes) {
        const float* p = rgb + 3 * t;
        const __m256 a0 = _mm256_loadu_ps(p), a1 = _mm256_loadu_ps(p + 8),
                     a2 = _mm256_loadu_ps(p + 16);
        highest = _mm256_max_epu32(highest, _mm256_castps_si256(a0));
        highest = _mm256_max_epu32(highest, _mm256_castps_si256(a1));
        highest = _mm256_max_epu32(highest, _mm256_castps_si256(a2));
        // Lane i of the blend takes a0, a1 or a2 as i mod 3 selects the wanted channel.
        const __m256 rb = _mm256_blend_ps(_mm256_blend_ps(a0, a1, 0x92), a2, 0x24);
        const __m256 gb = _mm256_blend_ps(_mm256_blend_ps(a0, a1, 0x24), a2, 0x49);
        const __m256 bb = _mm256_blend_ps(_mm256_blend_ps(a0, a1, 0x49), a2, 0x92);
        _mm256_storeu_ps(r + t, _mm256_permutevar8x32_ps(rb, orderR));
        _mm256_storeu_ps(g + t, _mm256_permutevar8x32_ps(gb, orderG));
        _mm256_storeu_ps(b + t, _mm256_permutevar8x32_ps(bb, orderB));
    }
    std::uint32_t limitBits;
    std::memcpy(&limitBits, &limit, sizeof limitBits);
    const __m256i top = _mm256_set1_epi32(int(limitBits));
    const bool vectorOk =
        _mm256_movemask_epi8(_mm256_cmpeq_epi32(_mm256_max_epu32(highest, top), top)) == -1;
    const bool rest = deinterleaveBaseline(rgb + 3 * t, m - t, limit, r + t, g + t, b + t);
    return vectorOk && rest;
}

__attribute__((target("avx2,fma"))) void multiplyAddAvx2(const float* weights, int padded,
                                                         const float* const planes[3], Sums out) {
    for (int k0 = 0; k0 < kShCoefficients; k0 += 3) {
        const float* w[3] = {weights + std::size_t(k0) * padded,
                             weights + std::size_t(k0 + 1) * padded,
                             weights + std::size_t(k0 + 2) * padded};
        __m256d total[3][3][2];
        for (auto& a : total)
            for (auto& v : a) v[0] = v[1] = _mm256_setzero_pd();
        for (int c0 = 0; c0 < padded; c0 += kChunkBlocks * kLanes) {
            const int end = std::min(padded, c0 + kChunkBlocks * kLanes);
            __m256 acc[3][3];
            for (auto& a : acc)
                for (auto& v : a) v = _mm256_setzero_ps();
            for (int t = c0; t < end; t += kLanes) {
                const __m256 dr = _mm256_loadu_ps(planes[0] + t);
                const __m256 dg = _mm256_loadu_ps(planes[1] + t);
                const __m256 db = _mm256_loadu_ps(planes[2] + t);
                for (int q = 0; q < 3; ++q) {
                    const __m256 wt = _mm256_loadu_ps(w[q] + t);
                    acc[q][0] = _mm256_fmadd_ps(wt, dr, acc[q][0]);
                    acc[q][1] = _mm256_fmadd_ps(wt, dg, acc[q][1]);
                    acc[q][2] = _mm256_fmadd_ps(wt, db, acc[q][2]);
                }
            }
            for (int q = 0; q < 3; ++q)
                for (int c = 0; c < 3; ++c) {
                    total[q][c][0] = _mm256_add_pd(
                        total[q][c][0], _mm256_cvtps_pd(_mm256_castps256_ps128(acc[q][c])));
                    total[q][c][1] = _mm256_add_pd(
                        total[q][c][1], _mm256_cvtps_pd(_mm256_extractf128_ps(acc[q][c], 1)));
                }
        }
        for (int q = 0; q < 3; ++q)
            for (int c = 0; c < 3; ++c) {
                double lanes[4];
                _mm256_storeu_pd(lanes, _mm256_add_pd(total[q][c][0], total[q][c][1]));
                out[k0 + q][c] = (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]);
            }
    }
}

// ---- Folded projection (even N, N / 2 a multiple of 8; AVX2 + FMA) ---------------------------
//
// On every face the world basis is a fixed linear mix of nine local functions of the face-
// normalised direction (u', v', w') = (u, v, 1) / r: u', v', w', u'v', u'w', v'w', u'^2, v'^2, w'^2
// (the face table is a signed permutation). Texel solid angles are symmetric under u -> -u and
// v -> -v, and each local function is even or odd in u and in v, so the four mirror images of a
// quadrant texel fold into four sums (even-even, odd-even, even-odd, odd-odd) and each local
// function needs only a quadrant-sized dot product: a quarter of the multiply-adds, with one
// small table shared by all six faces. A clean face (the common case) is de-interleaved, checked
// and folded in registers straight from its RGB texels; only a face that needs cleaning goes
// through the planes first.

// Parity class of each local function: 0 even-even, 1 odd in u, 2 odd in v, 3 odd in both.
constexpr int kLocalParity[kShCoefficients] = {1, 2, 0, 3, 1, 2, 0, 0, 0};

std::array<double, kShCoefficients> localFunctions(const glm::dvec3& p) {
    return {p.x, p.y, p.z, p.x * p.y, p.x * p.z, p.y * p.z, p.x * p.x, p.y * p.y, p.z * p.z};
}

// Lane i of the result is the sum of the eight lanes of v[i].
__attribute__((target("avx2,fma"), always_inline)) inline __m256 laneSums8(const __m256 (&v)[8]) {
    const __m256 t0 = _mm256_hadd_ps(v[0], v[1]), t1 = _mm256_hadd_ps(v[2], v[3]);
    const __m256 t2 = _mm256_hadd_ps(v[4], v[5]), t3 = _mm256_hadd_ps(v[6], v[7]);
    const __m256 u0 = _mm256_hadd_ps(t0, t1), u1 = _mm256_hadd_ps(t2, t3);
    return _mm256_add_ps(_mm256_permute2f128_ps(u0, u1, 0x20),
                         _mm256_permute2f128_ps(u0, u1, 0x31));
}

// out[s][f][c] = sum_q w[s][f][q] d[s][c][q] over `count` floats (a multiple of 8): D data sets
// of three channels, F functions per set, so each data vector is loaded once for F products.
// Float lanes are summed over at most kChunkBlocks vectors, reduced across lanes in float and
// then added in double.
template <int D, int F>
__attribute__((target("avx2,fma"), always_inline)) inline void dotSharedAvx2(
    const float* const (&w)[D][F], const float* const (&d)[D][3], int count,
    double (&out)[D][F][3]) {
    constexpr int kOut = D * F * 3, kGroups = (kOut + 7) / 8;
    double total[kGroups * 8] = {};
    for (int c0 = 0; c0 < count; c0 += kChunkBlocks * kLanes) {
        const int end = std::min(count, c0 + kChunkBlocks * kLanes);
        __m256 acc[kGroups * 8];
        for (auto& v : acc) v = _mm256_setzero_ps();
        for (int t = c0; t < end; t += kLanes) {
            for (int s = 0; s < D; ++s) {
                const __m256 data[3] = {_mm256_loadu_ps(d[s][0] + t), _mm256_loadu_ps(d[s][1] + t),
                                        _mm256_loadu_ps(d[s][2] + t)};
                for (int f = 0; f < F; ++f) {
                    const __m256 wt = _mm256_loadu_ps(w[s][f] + t);
                    for (int c = 0; c < 3; ++c) {
                        __m256& a = acc[(s * F + f) * 3 + c];
                        a = _mm256_fmadd_ps(wt, data[c], a);
                    }
                }
            }
        }
        for (int g = 0; g < kGroups; ++g) {
            __m256 v[8];
            for (int i = 0; i < 8; ++i) v[i] = acc[g * 8 + i];
            const __m256 sums = laneSums8(v);
            _mm256_storeu_pd(total + g * 8,
                             _mm256_add_pd(_mm256_loadu_pd(total + g * 8),
                                           _mm256_cvtps_pd(_mm256_castps256_ps128(sums))));
            _mm256_storeu_pd(total + g * 8 + 4,
                             _mm256_add_pd(_mm256_loadu_pd(total + g * 8 + 4),
                                           _mm256_cvtps_pd(_mm256_extractf128_ps(sums, 1))));
        }
    }
    for (int s = 0; s < D; ++s)
        for (int f = 0; f < F; ++f)
            for (int c = 0; c < 3; ++c) out[s][f][c] = total[(s * F + f) * 3 + c];
}

// The four mirror sums of one quadrant block (8 texels of rows jj and n-1-jj; a, cc the blocks
// at columns i0, b, d the mirrored blocks already reversed) into fold[parity][channel].
__attribute__((target("avx2,fma"), always_inline)) inline void storeMirrorSums(
    __m256 a, __m256 b, __m256 cc, __m256 d, float* p0, float* p1, float* p2, float* p3) {
    const __m256 s1 = _mm256_add_ps(a, b), d1 = _mm256_sub_ps(a, b);
    const __m256 s2 = _mm256_add_ps(cc, d), d2 = _mm256_sub_ps(cc, d);
    _mm256_storeu_ps(p0, _mm256_add_ps(s1, s2));
    _mm256_storeu_ps(p1, _mm256_add_ps(d1, d2));
    _mm256_storeu_ps(p2, _mm256_sub_ps(s1, s2));
    _mm256_storeu_ps(p3, _mm256_sub_ps(d1, d2));
}

// Folds de-interleaved N x N planes into fold[parity][channel][quarter texel].
__attribute__((target("avx2,fma"))) void foldPlanesAvx2(const float* const planes[3], int n,
                                                        float* fold) {
    const int half = n / 2, quarter = half * half;
    const __m256i reverse = _mm256_setr_epi32(7, 6, 5, 4, 3, 2, 1, 0);
    auto at = [&](int parity, int c) { return fold + (std::size_t(parity) * 3 + c) * quarter; };
    for (int c = 0; c < 3; ++c) {
        for (int jj = 0; jj < half; ++jj) {
            const float* rowA = planes[c] + std::size_t(jj) * n;
            const float* rowC = planes[c] + std::size_t(n - 1 - jj) * n;
            for (int i0 = 0; i0 < half; i0 += kLanes) {
                const __m256 b =
                    _mm256_permutevar8x32_ps(_mm256_loadu_ps(rowA + n - kLanes - i0), reverse);
                const __m256 d =
                    _mm256_permutevar8x32_ps(_mm256_loadu_ps(rowC + n - kLanes - i0), reverse);
                const std::size_t q = std::size_t(jj) * half + i0;
                storeMirrorSums(_mm256_loadu_ps(rowA + i0), b, _mm256_loadu_ps(rowC + i0), d,
                                at(0, c) + q, at(1, c) + q, at(2, c) + q, at(3, c) + q);
            }
        }
    }
}

// De-interleaves the 8 texels at p (24 floats) into r, g, b in texel order, or in reversed
// order when `reversed`, and folds the raw bits into `highest` (see deinterleaveAvx2).
__attribute__((target("avx2,fma"), always_inline)) inline void loadBlockAvx2(
    const float* p, bool reversed, __m256i& highest, __m256& r, __m256& g, __m256& b) {
    const __m256 a0 = _mm256_loadu_ps(p), a1 = _mm256_loadu_ps(p + 8), a2 = _mm256_loadu_ps(p + 16);
    highest = _mm256_max_epu32(highest, _mm256_castps_si256(a0));
    highest = _mm256_max_epu32(highest, _mm256_castps_si256(a1));
    highest = _mm256_max_epu32(highest, _mm256_castps_si256(a2));
    const __m256 rb = _mm256_blend_ps(_mm256_blend_ps(a0, a1, 0x92), a2, 0x24);
    const __m256 gb = _mm256_blend_ps(_mm256_blend_ps(a0, a1, 0x24), a2, 0x49);
    const __m256 bb = _mm256_blend_ps(_mm256_blend_ps(a0, a1, 0x49), a2, 0x92);
    if (reversed) {
        r = _mm256_permutevar8x32_ps(rb, _mm256_setr_epi32(5, 2, 7, 4, 1, 6, 3, 0));
        g = _mm256_permutevar8x32_ps(gb, _mm256_setr_epi32(6, 3, 0, 5, 2, 7, 4, 1));
        b = _mm256_permutevar8x32_ps(bb, _mm256_setr_epi32(7, 4, 1, 6, 3, 0, 5, 2));
    } else {
        r = _mm256_permutevar8x32_ps(rb, _mm256_setr_epi32(0, 3, 6, 1, 4, 7, 2, 5));
        g = _mm256_permutevar8x32_ps(gb, _mm256_setr_epi32(1, 4, 7, 2, 5, 0, 3, 6));
        b = _mm256_permutevar8x32_ps(bb, _mm256_setr_epi32(2, 5, 0, 3, 6, 1, 4, 7));
    }
}

// The same fold read straight from the interleaved face: de-interleave, mirror and check in
// registers, so the planes are never written. True when every value is in [+0, limit] (the
// check of deinterleaveAvx2); otherwise the caller takes the planes path, which cleans.
__attribute__((target("avx2,fma"))) bool foldInterleavedAvx2(const float* rgb, int n, float limit,
                                                             float* fold) {
    const int half = n / 2, quarter = half * half;
    __m256i highest = _mm256_setzero_si256();
    auto at = [&](int parity, int c) { return fold + (std::size_t(parity) * 3 + c) * quarter; };
    for (int jj = 0; jj < half; ++jj) {
        const float* rowA = rgb + 3 * std::size_t(jj) * n;
        const float* rowC = rgb + 3 * std::size_t(n - 1 - jj) * n;
        for (int i0 = 0; i0 < half; i0 += kLanes) {
            __m256 a[3], b[3], cc[3], d[3];
            loadBlockAvx2(rowA + 3 * i0, false, highest, a[0], a[1], a[2]);
            loadBlockAvx2(rowA + 3 * (n - kLanes - i0), true, highest, b[0], b[1], b[2]);
            loadBlockAvx2(rowC + 3 * i0, false, highest, cc[0], cc[1], cc[2]);
            loadBlockAvx2(rowC + 3 * (n - kLanes - i0), true, highest, d[0], d[1], d[2]);
            const std::size_t q = std::size_t(jj) * half + i0;
            for (int c = 0; c < 3; ++c)
                storeMirrorSums(a[c], b[c], cc[c], d[c], at(0, c) + q, at(1, c) + q, at(2, c) + q,
                                at(3, c) + q);
        }
    }
    std::uint32_t limitBits;
    std::memcpy(&limitBits, &limit, sizeof limitBits);
    const __m256i top = _mm256_set1_epi32(int(limitBits));
    return _mm256_movemask_epi8(_mm256_cmpeq_epi32(_mm256_max_epu32(highest, top), top)) == -1;
}

// The nine local sums from the folded quarters (see "Folded projection").
__attribute__((target("avx2,fma"))) void localSumsAvx2(int n, const float* local, const float* fold,
                                                       double sums[kShCoefficients][3]) {
    const int half = n / 2, quarter = half * half;
    auto at = [&](int parity, int c) { return fold + (std::size_t(parity) * 3 + c) * quarter; };
    auto w = [&](int j) { return local + std::size_t(j) * quarter; };
    auto planes = [&](int parity) {
        return std::array<const float*, 3>{at(parity, 0), at(parity, 1), at(parity, 2)};
    };
    auto keep = [&](int id, const double(&v)[3]) {
        for (int c = 0; c < 3; ++c) sums[id][c] = v[c];
    };
    {  // even-even: w', u'^2, v'^2, w'^2
        const auto p = planes(0);
        const float* const ws[1][4] = {{w(2), w(6), w(7), w(8)}};
        const float* const ds[1][3] = {{p[0], p[1], p[2]}};
        double out[1][4][3];
        dotSharedAvx2<1, 4>(ws, ds, quarter, out);
        keep(2, out[0][0]), keep(6, out[0][1]), keep(7, out[0][2]), keep(8, out[0][3]);
    }
    {  // odd in u: u', u'w'; odd in v: v', v'w'
        const auto pu = planes(1), pv = planes(2);
        const float* const ws[2][2] = {{w(0), w(4)}, {w(1), w(5)}};
        const float* const ds[2][3] = {{pu[0], pu[1], pu[2]}, {pv[0], pv[1], pv[2]}};
        double out[2][2][3];
        dotSharedAvx2<2, 2>(ws, ds, quarter, out);
        keep(0, out[0][0]), keep(4, out[0][1]), keep(1, out[1][0]), keep(5, out[1][1]);
    }
    {  // odd-odd: u'v'
        const auto p = planes(3);
        const float* const ws[1][1] = {{w(3)}};
        const float* const ds[1][3] = {{p[0], p[1], p[2]}};
        double out[1][1][3];
        dotSharedAvx2<1, 1>(ws, ds, quarter, out);
        keep(3, out[0][0]);
    }
}

bool cpuHasAvx2Fma() {
    static const bool has = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
    return has;
}

#endif

// De-interleaves `m` texels into the planes; true when all are clean (see above).
bool deinterleave(bool avx2, const float* rgb, int m, float limit, float* r, float* g, float* b) {
#ifdef AMB_PROJECTOR_AVX2
    if (avx2 && cpuHasAvx2Fma()) return deinterleaveAvx2(rgb, m, limit, r, g, b);
#endif
    (void)avx2;
    return deinterleaveBaseline(rgb, m, limit, r, g, b);
}

void multiplyAdd(bool avx2, const float* weights, int padded, const float* const planes[3],
                 Sums out) {
#ifdef AMB_PROJECTOR_AVX2
    if (avx2 && cpuHasAvx2Fma()) return multiplyAddAvx2(weights, padded, planes, out);
#endif
    (void)avx2;
    multiplyAddBaseline(weights, padded, planes, out);
}

}  // namespace

// ---- Texel solid angles ----------------------------------------------------------------------

double cubeTexelSolidAngle(int i, int j, int n) {
    const double x0 = faceCoordinate(i, n), x1 = faceCoordinate(i + 1, n);
    const double y0 = faceCoordinate(j, n), y1 = faceCoordinate(j + 1, n);
    return areaTerm(x0, y0) - areaTerm(x0, y1) - areaTerm(x1, y0) + areaTerm(x1, y1);
}

// ---- Basis textures --------------------------------------------------------------------------

// For each face and coefficient k, the N^2 products omega(texel) Y_k(direction(texel)) in float,
// zero-padded to whole blocks of texels: weights[(face * 9 + k) * padded + j * N + i].
struct CubeMapProjector::Table {
    int n = 0;
    int padded = 0;  // texels per face, rounded up to whole blocks
    std::vector<float> weights;

    // The folded form (see "Folded projection"): local[j][q] = omega(q) phi_j(q) over the
    // quadrant u, v < 0, and per face the mix from the nine local sums to the nine coefficients.
    bool foldable = false;
    std::vector<float> local;
    std::array<std::array<std::array<double, kShCoefficients>, kShCoefficients>, kCubeFaces> mix{};
    // The non-zero entries of mix per coefficient: a signed permutation, with two or three
    // terms for the m = 0 and m = 2 functions of bands 0 and 2.
    struct MixRow {
        int count = 0;
        std::array<int, 3> f{};
        std::array<double, 3> weight{};
    };
    std::array<std::array<MixRow, kShCoefficients>, kCubeFaces> mixRows{};

    explicit Table(int faceSize) : n(faceSize), padded(paddedTexels(faceSize)) {
        buildFull();
#ifdef AMB_PROJECTOR_AVX2
        foldable = n % (2 * kLanes) == 0;
#endif
        if (foldable) buildFolded();
    }

    void buildFull() {
        weights.assign(std::size_t(kCubeFaces) * kShCoefficients * padded, 0.0f);
        for (int face = 0; face < kCubeFaces; ++face) {
            for (int j = 0; j < n; ++j) {
                for (int i = 0; i < n; ++i) {
                    const double omega = cubeTexelSolidAngle(i, j, n);
                    const auto y = shBasis(glm::normalize(cubeTexelDirection(face, i, j, n)));
                    for (int k = 0; k < kShCoefficients; ++k) {
                        weights[(std::size_t(face) * kShCoefficients + k) * padded + j * n + i] =
                            float(omega * y[k]);
                    }
                }
            }
        }
    }

    void buildFolded() {
        const int half = n / 2;
        local.assign(std::size_t(kShCoefficients) * half * half, 0.0f);
        for (int j = 0; j < half; ++j)
            for (int i = 0; i < half; ++i) {
                const double omega = cubeTexelSolidAngle(i, j, n);
                const glm::dvec3 p = glm::normalize(glm::dvec3(
                    faceCoordinate(2 * i + 1, 2 * n), faceCoordinate(2 * j + 1, 2 * n), 1.0));
                const auto phi = localFunctions(p);
                for (int f = 0; f < kShCoefficients; ++f)
                    local[std::size_t(f) * half * half + j * half + i] = float(omega * phi[f]);
            }
        // Mix: Y_k(A p) = sum_f mix[k][f] phi_f(p) for unit p, A the face's linear map
        // (u, v, 1) -> world direction; solved exactly from nine generic unit points.
        for (int face = 0; face < kCubeFaces; ++face) {
            const glm::dvec3 origin = cubeFaceDirection(face, 0.0, 0.0);
            const glm::dvec3 eu = cubeFaceDirection(face, 1.0, 0.0) - origin;
            const glm::dvec3 ev = cubeFaceDirection(face, 0.0, 1.0) - origin;
            double a[kShCoefficients][kShCoefficients];
            double rhs[kShCoefficients][kShCoefficients];
            for (int s = 0; s < kShCoefficients; ++s) {
                const glm::dvec3 p = glm::normalize(
                    glm::dvec3(std::sin(1.3 * s + 0.2), std::cos(2.1 * s + 0.7), 0.9 - 0.23 * s));
                const auto phi = localFunctions(p);
                const auto y = shBasis(p.x * eu + p.y * ev + p.z * origin);
                for (int f = 0; f < kShCoefficients; ++f) a[s][f] = phi[f];
                for (int k = 0; k < kShCoefficients; ++k) rhs[s][k] = y[k];
            }
            // Gaussian elimination with partial pivoting, nine right-hand sides.
            for (int col = 0; col < kShCoefficients; ++col) {
                int pivot = col;
                for (int r = col + 1; r < kShCoefficients; ++r)
                    if (std::abs(a[r][col]) > std::abs(a[pivot][col])) pivot = r;
                std::swap(a[col], a[pivot]);
                std::swap(rhs[col], rhs[pivot]);
                AMB_CHECK(std::abs(a[col][col]) > 1e-9);
                for (int r = 0; r < kShCoefficients; ++r) {
                    if (r == col) continue;
                    const double factor = a[r][col] / a[col][col];
                    for (int c = 0; c < kShCoefficients; ++c) a[r][c] -= factor * a[col][c];
                    for (int k = 0; k < kShCoefficients; ++k) rhs[r][k] -= factor * rhs[col][k];
                }
            }
            for (int f = 0; f < kShCoefficients; ++f)
                for (int k = 0; k < kShCoefficients; ++k) {
                    const double v = rhs[f][k] / a[f][f];
                    mix[face][k][f] = std::abs(v) < 1e-12 ? 0.0 : v;  // exact zeros stay zero
                    if (mix[face][k][f] == 0.0) continue;
                    MixRow& row = mixRows[face][k];
                    AMB_CHECK(row.count < 3);
                    row.f[row.count] = f;
                    row.weight[row.count++] = v;
                }
        }
    }

    static std::shared_ptr<const Table> get(int faceSize) {
        static std::mutex mutex;
        static std::map<int, std::shared_ptr<const Table>> cache;
        std::lock_guard<std::mutex> lock(mutex);
        auto& slot = cache[faceSize];
        if (!slot) slot = std::make_shared<const Table>(faceSize);
        return slot;
    }
};

CubeMapProjector::CubeMapProjector(int faceSize) : CubeMapProjector(faceSize, Options{}) {}

CubeMapProjector::CubeMapProjector(int faceSize, const Options& options)
    : n_(faceSize), options_(options) {
    AMB_CHECK(faceSize >= 1);
    if (faceSize <= kTableMaxFaceSize) {
        table_ = Table::get(faceSize);
        // Three planes (zero padding stays zero), then the folded sums (4 x 3 quarters), plus
        // one block of slack so that the planes start on a 32-byte boundary.
        scratch_.assign(
            3 * std::size_t(table_->padded) + 3 * std::size_t(faceSize) * faceSize + kLanes, 0.0f);
    }
}

// ---- Projection of one face ------------------------------------------------------------------

void CubeMapProjector::addFace(int face, const float* rgb,
                               const std::optional<glm::dvec3>& sunDirection) {
    AMB_CHECK(face >= 0 && face < kCubeFaces);
    // Filled in place: each path sets every coefficient, the sun sums and counts start at zero.
    FaceSum& sum = faces_[face];
    sum.sunIrradiance = {};
    sum.sunDirection = {};
    sum.bad = 0;
    // The sun's texel (SunTexel.h): projected from a copy with that texel filled from its
    // neighbours; what the fill took away is the directional light, along the sun direction.
    const CubeTexel t = sunDirection ? sunTexel(*sunDirection, n_) : CubeTexel{-1, 0, 0};
    if (t.face == face) {
        sunFace_.assign(rgb, rgb + 3 * std::size_t(n_) * n_);
        glm::vec3 removed, filled;
        if (fillSunTexel(sunFace_.data(), face, n_, *sunDirection, &removed, &filled)) {
            rgb = sunFace_.data();
            const double omega = cubeTexelSolidAngle(t.i, t.j, n_);
            const glm::dvec3 excess = glm::max(glm::dvec3(removed) - glm::dvec3(filled), 0.0);
            const glm::dvec3 dir = glm::normalize(*sunDirection);
            const double w = omega * luminance(excess.x, excess.y, excess.z);
            for (int c = 0; c < 3; ++c) {
                sum.sunIrradiance[c] += omega * excess[c];
                sum.sunDirection[c] += w * dir[c];
            }
        }
    }
    if (table_) {
        projectTable(face, rgb, sum);
    } else {
        projectStreaming(face, rgb, sum);
    }
    sum.present = true;
}

void CubeMapProjector::addCubeMap(const float* rgb, const std::optional<glm::dvec3>& sunDirection) {
    const std::size_t faceFloats = 3 * std::size_t(n_) * n_;
    for (int face = 0; face < kCubeFaces; ++face)
        addFace(face, rgb + face * faceFloats, sunDirection);
}

void CubeMapProjector::takeSunTexel(int face, int i, int j, float r, float g, float b,
                                    FaceSum& sum) const {
    const double omega = cubeTexelSolidAngle(i, j, n_);
    const glm::dvec3 dir = glm::normalize(cubeTexelDirection(face, i, j, n_));
    sum.sunIrradiance[0] += omega * r;
    sum.sunIrradiance[1] += omega * g;
    sum.sunIrradiance[2] += omega * b;
    const double w = omega * luminance(r, g, b);
    for (int a = 0; a < 3; ++a) sum.sunDirection[a] += w * dir[a];
}

// Table path: de-interleave (and check) the face, clean it only when the check fails (zero and
// count bad texels, move sun texels to the directional light), then the multiply-add.
void CubeMapProjector::projectTable(int face, const float* rgb, FaceSum& sum) {
    const int m = n_ * n_;
    const int padded = table_->padded;
    float* r = scratch_.data();
    r += (kLanes - (reinterpret_cast<std::uintptr_t>(r) / sizeof(float)) % kLanes) % kLanes;
    float* g = r + padded;
    float* b = g + padded;
    const float limit =
        options_.sunThreshold < double(FLT_MAX) ? float(options_.sunThreshold) : FLT_MAX;
#ifdef AMB_PROJECTOR_AVX2
    const bool folded = table_->foldable && options_.allowAvx2 && cpuHasAvx2Fma();
    float* fold = b + padded;
    // Clean faces (the common case) fold straight from the interleaved texels.
    const bool cleanFolded = folded && foldInterleavedAvx2(rgb, n_, limit, fold);
#else
    const bool folded = false, cleanFolded = false;
#endif
    if (!cleanFolded && !deinterleave(options_.allowAvx2, rgb, m, limit, r, g, b)) {
        for (int t = 0; t < m; ++t) {
            if (!(usable(r[t]) && usable(g[t]) && usable(b[t]))) {
                ++sum.bad;
                r[t] = g[t] = b[t] = 0.0f;
            } else if (luminance(r[t], g[t], b[t]) > options_.sunThreshold) {
                takeSunTexel(face, t % n_, t / n_, r[t], g[t], b[t], sum);
                r[t] = g[t] = b[t] = 0.0f;
            }
        }
    }
    const float* const planes[3] = {r, g, b};
#ifdef AMB_PROJECTOR_AVX2
    if (folded) {
        if (!cleanFolded) foldPlanesAvx2(planes, n_, fold);
        double local[kShCoefficients][3];
        localSumsAvx2(n_, table_->local.data(), fold, local);
        for (int k = 0; k < kShCoefficients; ++k) {
            const Table::MixRow& row = table_->mixRows[face][k];
            for (int c = 0; c < 3; ++c) {
                double v = 0.0;
                for (int t = 0; t < row.count; ++t) v += row.weight[t] * local[row.f[t]][c];
                sum.sh[k][c] = v;
            }
        }
        return;
    }
#endif
    (void)folded;
    Sums out;
    const float* weights = table_->weights.data() + std::size_t(face) * kShCoefficients * padded;
    multiplyAdd(options_.allowAvx2, weights, padded, planes, out);
    for (int k = 0; k < kShCoefficients; ++k) sum.sh[k] = {out[k][0], out[k][1], out[k][2]};
}

// Streaming path (N > kTableMaxFaceSize): solid angles from a rolling row of corner area terms,
// basis and products in double, one double row sum added to the face sum per row.
void CubeMapProjector::projectStreaming(int face, const float* rgb, FaceSum& sum) {
    const int n = n_;
    sum.sh = {};
    std::vector<double> below(n + 1), above(n + 1);  // area terms at corner rows j and j + 1
    for (int a = 0; a <= n; ++a) below[a] = areaTerm(faceCoordinate(a, n), faceCoordinate(0, n));
    for (int j = 0; j < n; ++j) {
        const double y1 = faceCoordinate(j + 1, n);
        for (int a = 0; a <= n; ++a) above[a] = areaTerm(faceCoordinate(a, n), y1);
        std::array<std::array<double, 3>, kShCoefficients> row{};
        for (int i = 0; i < n; ++i) {
            const float* p = rgb + 3 * (std::size_t(j) * n + i);
            if (!(usable(p[0]) && usable(p[1]) && usable(p[2]))) {
                ++sum.bad;
                continue;
            }
            if (luminance(p[0], p[1], p[2]) > options_.sunThreshold) {
                takeSunTexel(face, i, j, p[0], p[1], p[2], sum);
                continue;
            }
            const double omega = below[i] - above[i] - below[i + 1] + above[i + 1];
            const auto y = shBasis(glm::normalize(cubeTexelDirection(face, i, j, n)));
            for (int k = 0; k < kShCoefficients; ++k) {
                const double wy = omega * y[k];
                row[k][0] += wy * p[0];
                row[k][1] += wy * p[1];
                row[k][2] += wy * p[2];
            }
        }
        for (int k = 0; k < kShCoefficients; ++k) {
            for (int c = 0; c < 3; ++c) sum.sh[k][c] += row[k][c];
        }
        std::swap(below, above);
    }
}

// ---- Sums and whole-map projection -----------------------------------------------------------

void CubeMapProjector::reset() {
    faces_ = {};
}

int CubeMapProjector::facesAdded() const {
    int count = 0;
    for (const auto& f : faces_) count += f.present;
    return count;
}

bool CubeMapProjector::complete() const {
    return facesAdded() == kCubeFaces;
}

ShRgbD CubeMapProjector::coefficients() const {
    ShRgbD sh;
    for (const auto& f : faces_) {
        for (int k = 0; k < kShCoefficients; ++k) {
            sh.c[k] += glm::dvec3(f.sh[k][0], f.sh[k][1], f.sh[k][2]);
        }
    }
    return sh;
}

DirectionalLight CubeMapProjector::sun() const {
    DirectionalLight light;
    glm::dvec3 dir(0.0);
    for (const auto& f : faces_) {
        light.irradiance += glm::dvec3(f.sunIrradiance[0], f.sunIrradiance[1], f.sunIrradiance[2]);
        dir += glm::dvec3(f.sunDirection[0], f.sunDirection[1], f.sunDirection[2]);
    }
    if (glm::length(dir) > 0.0) light.direction = glm::normalize(dir);
    return light;
}

std::int64_t CubeMapProjector::badTexels() const {
    std::int64_t bad = 0;
    for (const auto& f : faces_) bad += f.bad;
    return bad;
}

CubeMapProjection projectCubeMap(int n, const std::vector<float>& rgb,
                                 const CubeMapProjector::Options& options,
                                 const std::optional<glm::dvec3>& sunDirection) {
    AMB_CHECK(n >= 1 && rgb.size() == std::size_t(kCubeFaces) * n * n * 3);
    CubeMapProjector projector(n, options);
    projector.addCubeMap(rgb.data(), sunDirection);
    return {projector.coefficients(), projector.sun(), projector.badTexels()};
}

}  // namespace amb
