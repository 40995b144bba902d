#include "physics/hull_cache.hpp"

#include <BulletCollision/CollisionShapes/btConvexPolyhedron.h>

#include <cstring>
#include <list>
#include <mutex>
#include <string>
#include <type_traits>
#include <unordered_map>
#include <utility>

namespace mgn::physics {

namespace {

template <class T>
void append(std::string& key, const T& value) {
  static_assert(std::is_trivially_copyable_v<T>);
  key.append(reinterpret_cast<const char*>(&value), sizeof(T));
}

/// Every input of the preparation, as bytes (see hull_cache.hpp).
std::string key_of(const RigidObject& object, const PrincipalFrame& principal,
                   const BulletUnits& units, const HullShapeOptions& o) {
  std::size_t size = 64 + 16 * sizeof(double);
  for (const Mesh& part : object.convex_parts)
    size +=
        sizeof(std::int64_t) + 3 * sizeof(float) * static_cast<std::size_t>(part.num_vertices());
  std::string key;
  key.reserve(size);
  append(key, units.length);
  append(key, static_cast<std::int32_t>(o.reduction));
  append(key, static_cast<std::int32_t>(o.max_vertices));
  append(key, o.tolerance);
  append(key, o.margin);
  append(key, static_cast<std::uint8_t>(o.shrink_by_margin));
  append(key, static_cast<std::uint8_t>(o.polyhedral));
  const Mat4d X_OB = principal.X_OB.matrix();
  key.append(reinterpret_cast<const char*>(X_OB.data()), 16 * sizeof(double));
  append(key, static_cast<std::int64_t>(object.convex_parts.size()));
  for (const Mesh& part : object.convex_parts) {
    const Points3f& V = part.vertices();  // row-major: x, y, z of each vertex in order
    append(key, static_cast<std::int64_t>(V.rows()));
    key.append(reinterpret_cast<const char*>(V.data()),
               3 * sizeof(float) * static_cast<std::size_t>(V.rows()));
  }
  return key;
}

/// Estimated memory of one hull shape: its object, vertex arrays (Bullet grows an array to
/// the next power of two), support-search arrays and polyhedral features, and about kAlloc bytes
/// of allocator overhead per allocation.
std::size_t shape_bytes(const btConvexHullShape& s) {
  constexpr std::size_t kAlloc = 48;
  const auto n = static_cast<std::size_t>(s.getNumPoints());
  std::size_t grown = 1;
  while (grown < n) grown *= 2;
  std::size_t bytes =
      sizeof(btConvexHullShape) + 64 + 16 * grown + 12 * ((n + 7) / 8 * 8) + 4 * kAlloc;
  if (const btConvexPolyhedron* p = s.getConvexPolyhedron()) {
    bytes += sizeof(btConvexPolyhedron) + 16 * static_cast<std::size_t>(p->m_vertices.capacity()) +
             16 * static_cast<std::size_t>(p->m_uniqueEdges.capacity()) +
             sizeof(btFace) * static_cast<std::size_t>(p->m_faces.capacity()) + 4 * kAlloc;
    for (int f = 0; f < p->m_faces.size(); ++f)
      bytes += sizeof(int) * static_cast<std::size_t>(p->m_faces[f].m_indices.capacity()) + kAlloc;
  }
  return bytes;
}

std::shared_ptr<const PreparedHulls> prepare(const RigidObject& object,
                                             const PrincipalFrame& principal,
                                             const BulletUnits& units,
                                             const HullShapeOptions& options,
                                             std::size_t key_bytes) {
  auto out = std::make_shared<PreparedHulls>();
  const RigidGeometry geometry = rigid_geometry(object, principal, units, options);
  out->bytes = sizeof(PreparedHulls) + 256 + key_bytes;  // 256: the cache's list and index nodes
  for (const HullPoints& h : geometry.hulls) {
    out->hulls.push_back(hull_shape(h, units, options));
    out->bytes += shape_bytes(*out->hulls.back());
  }
  return out;
}

/// The process-wide cache: an LRU list of entries (front: most recently used) and an index.
class HullCache {
 public:
  std::shared_ptr<const PreparedHulls> get(const RigidObject& object,
                                           const PrincipalFrame& principal,
                                           const BulletUnits& units,
                                           const HullShapeOptions& options) {
    std::string key = key_of(object, principal, units, options);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      const auto it = capacity_ == 0 ? index_.end() : index_.find(key);
      if (it != index_.end()) {
        ++hits_;
        lru_.splice(lru_.begin(), lru_, it->second);  // most recently used
        return it->second->value;
      }
      ++misses_;  // not cached, or nothing is (capacity 0)
    }
    // Prepared outside the lock: other threads' simulations do not wait for it.
    std::shared_ptr<const PreparedHulls> value =
        prepare(object, principal, units, options, key.size());
    std::lock_guard<std::mutex> lock(mutex_);
    if (value->bytes > capacity_) return value;  // does not fit (or nothing is cached)
    if (const auto it = index_.find(key); it != index_.end()) {
      // Another thread prepared the same inputs meanwhile: the same shapes; keep one.
      lru_.splice(lru_.begin(), lru_, it->second);
      return it->second->value;
    }
    lru_.push_front(Entry{key, value});
    index_.emplace(std::move(key), lru_.begin());
    bytes_ += value->bytes;
    evict();
    return value;
  }

  HullCacheInfo info() const {
    std::lock_guard<std::mutex> lock(mutex_);
    HullCacheInfo i;
    i.entries = lru_.size();
    i.bytes = bytes_;
    i.capacity = capacity_;
    i.hits = hits_;
    i.misses = misses_;
    i.evictions = evictions_;
    return i;
  }

  void clear() {
    std::lock_guard<std::mutex> lock(mutex_);
    index_.clear();
    lru_.clear();
    bytes_ = 0;
    hits_ = misses_ = evictions_ = 0;
  }

  void set_capacity(std::size_t bytes) {
    std::lock_guard<std::mutex> lock(mutex_);
    capacity_ = bytes;
    evict();
  }

 private:
  struct Entry {
    std::string key;
    std::shared_ptr<const PreparedHulls> value;
  };

  /// Least recently used entries go until the rest fits the capacity (mutex_ held).
  void evict() {
    while (bytes_ > capacity_ && !lru_.empty()) {
      bytes_ -= lru_.back().value->bytes;
      index_.erase(lru_.back().key);
      lru_.pop_back();
      ++evictions_;
    }
  }

  mutable std::mutex mutex_;
  std::list<Entry> lru_;
  std::unordered_map<std::string, std::list<Entry>::iterator> index_;
  std::size_t bytes_ = 0;
  std::size_t capacity_ = kDefaultHullCacheCapacity;
  std::int64_t hits_ = 0, misses_ = 0, evictions_ = 0;
};

HullCache& cache() {
  static HullCache c;  // constructed on first use (thread-safe), lives until exit
  return c;
}

}  // namespace

std::shared_ptr<const PreparedHulls> prepared_hulls(const RigidObject& object,
                                                    const PrincipalFrame& principal,
                                                    const BulletUnits& units,
                                                    const HullShapeOptions& options) {
  return cache().get(object, principal, units, options);
}

HullCacheInfo hull_cache_info() { return cache().info(); }

void clear_hull_cache() { cache().clear(); }

void set_hull_cache_capacity(std::size_t bytes) { cache().set_capacity(bytes); }

}  // namespace mgn::physics
