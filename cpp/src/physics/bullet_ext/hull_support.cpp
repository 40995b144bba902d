#include "physics/bullet_ext/hull_support.hpp"

#include <algorithm>
#include <atomic>
#include <cstddef>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define MGN_HULL_SUPPORT_X86 1
#endif

// This file is compiled with -ffp-contract=off (cpp/CMakeLists.txt): a fused multiply-add would
// round differently from Bullet's scan and could pick another vertex.

namespace mgn::physics {

static_assert(sizeof(btScalar) == sizeof(float), "HullSupport expects Bullet in single precision");

namespace {

constexpr int kPad = 8;

/// Lanes' best dot products and indices -> the first index of the largest dot product.
long reduce(const float* best, const float* index, int lanes, btScalar& dot) {
  float m = -SIMD_INFINITY;
  long at = -1;
  for (int k = 0; k < lanes; ++k) {
    if (index[k] < 0) continue;
    const long i = static_cast<long>(index[k]);
    if (best[k] > m || (best[k] == m && (at < 0 || i < at))) {
      m = best[k];
      at = i;
    }
  }
  dot = m;
  return at;
}

#ifdef MGN_HULL_SUPPORT_X86

/// Four vertices at a time (SSE2, every x86-64). Each lane keeps its first strict maximum, as
/// the scalar scan does over the vertices of that lane.
long argmax_sse2(const float* x, const float* y, const float* z, int n, float dx, float dy,
                 float dz, btScalar& dot) {
  const __m128 vx = _mm_set1_ps(dx), vy = _mm_set1_ps(dy), vz = _mm_set1_ps(dz);
  const __m128 four = _mm_set1_ps(4.0f);
  __m128 best = _mm_set1_ps(-SIMD_INFINITY);
  __m128 best_index = _mm_set1_ps(-1.0f);
  __m128 index = _mm_setr_ps(0.0f, 1.0f, 2.0f, 3.0f);
  for (int i = 0; i < n; i += 4) {
    const __m128 d = _mm_add_ps(
        _mm_add_ps(_mm_mul_ps(_mm_loadu_ps(x + i), vx), _mm_mul_ps(_mm_loadu_ps(y + i), vy)),
        _mm_mul_ps(_mm_loadu_ps(z + i), vz));
    const __m128 gt = _mm_cmpgt_ps(d, best);
    best = _mm_or_ps(_mm_and_ps(gt, d), _mm_andnot_ps(gt, best));
    best_index = _mm_or_ps(_mm_and_ps(gt, index), _mm_andnot_ps(gt, best_index));
    index = _mm_add_ps(index, four);
  }
  alignas(16) float b[4], k[4];
  _mm_store_ps(b, best);
  _mm_store_ps(k, best_index);
  return reduce(b, k, 4, dot);
}

/// Dot products of vertices i..i+7 with (vx, vy, vz), as the scalar scan rounds them.
__attribute__((target("avx"), always_inline)) inline __m256 dots8(const float* x, const float* y,
                                                                  const float* z, int i, __m256 vx,
                                                                  __m256 vy, __m256 vz) {
  return _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(_mm256_loadu_ps(x + i), vx),
                                     _mm256_mul_ps(_mm256_loadu_ps(y + i), vy)),
                       _mm256_mul_ps(_mm256_loadu_ps(z + i), vz));
}

/// Eight vertices at a time (AVX, chosen at run time), in two passes: the largest dot product
/// (two independent running maxima), then the first vertex whose dot product, computed again
/// with the same operations, equals it. _mm256_max_ps(d, m) is m unless d > m, so NaNs are
/// skipped and the maximum is the scan's; ties (+0 and -0 included) go to the first vertex.
__attribute__((target("avx"))) long argmax_avx(const float* x, const float* y, const float* z,
                                               int n, float dx, float dy, float dz, btScalar& dot) {
  const __m256 vx = _mm256_set1_ps(dx), vy = _mm256_set1_ps(dy), vz = _mm256_set1_ps(dz);
  __m256 m0 = _mm256_set1_ps(-SIMD_INFINITY), m1 = m0;
  int i = 0;
  for (; i + 16 <= n; i += 16) {
    m0 = _mm256_max_ps(dots8(x, y, z, i, vx, vy, vz), m0);
    m1 = _mm256_max_ps(dots8(x, y, z, i + 8, vx, vy, vz), m1);
  }
  if (i < n) m0 = _mm256_max_ps(dots8(x, y, z, i, vx, vy, vz), m0);
  // NaN-free from here (the initial value and dot products that beat it).
  __m256 m = _mm256_max_ps(m0, m1);
  m = _mm256_max_ps(m, _mm256_permute2f128_ps(m, m, 1));
  m = _mm256_max_ps(m, _mm256_shuffle_ps(m, m, _MM_SHUFFLE(1, 0, 3, 2)));
  m = _mm256_max_ps(m, _mm256_shuffle_ps(m, m, _MM_SHUFFLE(2, 3, 0, 1)));
  const float best = _mm256_cvtss_f32(m);
  dot = -SIMD_INFINITY;
  if (!(best > -SIMD_INFINITY)) return -1;  // no dot product beats the scan's start value
  for (int j = 0; j < n; j += 8) {
    const __m256 d = dots8(x, y, z, j, vx, vy, vz);
    const int hit = _mm256_movemask_ps(_mm256_cmp_ps(d, m, _CMP_EQ_OQ));
    if (hit != 0) {
      const int k = __builtin_ctz(static_cast<unsigned>(hit));
      alignas(32) float v[8];
      _mm256_store_ps(v, d);
      dot = v[k];  // the first maximum's own value (its sign, if it is a zero)
      return j + k;
    }
  }
  return -1;  // not reached: the maximum is one of the dot products
}

#endif

int best_width() {
#ifdef MGN_HULL_SUPPORT_X86
  __builtin_cpu_init();  // called from a static initialiser, possibly before libgcc's
  return __builtin_cpu_supports("avx") ? 8 : 4;
#else
  return 1;
#endif
}

std::atomic<int> g_width{best_width()};

/// The scalar scan (other processors), as btVector3::maxDot.
long argmax_scalar(const float* x, const float* y, const float* z, int n, float dx, float dy,
                   float dz, btScalar& dot) {
  float m = -SIMD_INFINITY;
  long at = -1;
  for (int i = 0; i < n; ++i) {
    const float v = x[i] * dx + y[i] * dy + z[i] * dz;
    if (v > m) {
      m = v;
      at = i;
    }
  }
  dot = m;
  return at;
}

}  // namespace

HullSupport::HullSupport(const btVector3* points, int count) : count_(count) {
  if (count <= 0) return;
  const std::size_t padded = (static_cast<std::size_t>(count) + kPad - 1) / kPad * kPad;
  // Padding repeats vertex 0: its dot products tie with vertex 0's, which comes first.
  x_.assign(padded, points[0].x());
  y_.assign(padded, points[0].y());
  z_.assign(padded, points[0].z());
  for (int i = 0; i < count; ++i) {
    x_[static_cast<std::size_t>(i)] = points[i].x();
    y_[static_cast<std::size_t>(i)] = points[i].y();
    z_[static_cast<std::size_t>(i)] = points[i].z();
  }
}

long HullSupport::argmax(const btVector3& d, btScalar& dot) const {
  if (count_ <= 0) {
    dot = -SIMD_INFINITY;
    return -1;
  }
  const int n = static_cast<int>(x_.size());
#ifdef MGN_HULL_SUPPORT_X86
  switch (g_width.load(std::memory_order_relaxed)) {
    case 8:
      return argmax_avx(x_.data(), y_.data(), z_.data(), n, d.x(), d.y(), d.z(), dot);
    case 4:
      return argmax_sse2(x_.data(), y_.data(), z_.data(), n, d.x(), d.y(), d.z(), dot);
    default:
      break;
  }
#endif
  return argmax_scalar(x_.data(), y_.data(), z_.data(), count_, d.x(), d.y(), d.z(), dot);
}

int HullSupport::set_width(int width) {
  const int best = best_width();
  const int w = width == 8 || width == 4 || width == 1 ? std::min(width, best) : best;
  g_width.store(w, std::memory_order_relaxed);
  return w;
}

FastHullShape::FastHullShape(const std::vector<btVector3>& points) {
  for (const btVector3& p : points) addPoint(p, false);
  support_ = HullSupport(getUnscaledPoints(), getNumPoints());
  m_shapeType = CUSTOM_POLYHEDRAL_SHAPE_TYPE;
}

// As btConvexHullShape's own functions, with the scan replaced.
btVector3 FastHullShape::localGetSupportingVertexWithoutMargin(const btVector3& vec) const {
  if (support_.size() == 0) return btVector3(0, 0, 0);
  btScalar dot;
  long i = support_.argmax(vec * getLocalScaling(), dot);
  if (i < 0) i = 0;
  return support_.vertex(i) * getLocalScaling();  // = getUnscaledPoints()[i] * scaling
}

void FastHullShape::batchedUnitVectorGetSupportingVertexWithoutMargin(const btVector3* vectors,
                                                                      btVector3* supportVerticesOut,
                                                                      int numVectors) const {
  for (int j = 0; j < numVectors; ++j) {
    if (support_.size() == 0) {
      supportVerticesOut[j][3] = btScalar(-BT_LARGE_FLOAT);
      continue;
    }
    btScalar dot;
    long i = support_.argmax(vectors[j] * getLocalScaling(), dot);
    if (i < 0) i = 0;
    supportVerticesOut[j] = support_.vertex(i) * getLocalScaling();  // = getScaledPoint(i)
    supportVerticesOut[j][3] = dot;
  }
}

}  // namespace mgn::physics
