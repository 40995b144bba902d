#pragma once
// Prepared hull shapes of rigid objects, kept between simulations (private: Bullet types do not
// appear in installed headers). Used by the drop (scene/drop.cpp): a dataset drops the same
// catalogue objects scene after scene, and preparing an object's hulls (the hull of each part,
// its outer reduction, Bullet's hull shape with its support-search arrays and polyhedral
// features) is the same work with the same result every time.
//
// An entry is keyed by every input of the preparation, compared bit for bit: the vertices of
// every convex part (float, in order; a part's faces are not read, each part is the convex hull
// of its vertices), the principal frame X_OB, the Bullet units and every HullShapeOptions field.
// A changed mesh, scale, inertia or option is a different key, never a stale entry; an entry
// holds exactly what a fresh preparation builds, so a simulation is the same bit for bit with
// or without the cache.
//
// Thread safety: the cache is process-wide; one mutex guards its index. Entries are shared
// (std::shared_ptr) and never modified after they are built: a simulation only reads its hull
// shapes (support queries, bounding boxes, polyhedral features), so one entry serves any
// number of bodies, worlds and threads at once, and an entry evicted while a simulation uses it
// lives until that simulation ends. Memory: least recently used entries are evicted beyond the
// capacity (bytes, estimated: the shapes' vertex arrays, support-search arrays, polyhedra and
// the key; default kDefaultHullCacheCapacity).
#include "physics/bullet.hpp"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace mgn::physics {

/// The Bullet hull shapes of one rigid object's parts in its principal frame (one per part, in
/// part order, as rigid_shape() builds them), read-only once built.
struct PreparedHulls {
  std::vector<std::unique_ptr<btConvexHullShape>> hulls;
  std::size_t bytes = 0;  ///< estimated memory of the shapes and of the entry's key
};

/// The hull shapes of `object` in `principal` for `units` and `options`: the cached entry
/// prepared from the same inputs (see the file comment), else prepared now (rigid_geometry()
/// and hull_shape(), exactly as rigid_shape() does) and cached if it fits the capacity. Throws
/// what the preparation throws (nothing is cached then).
std::shared_ptr<const PreparedHulls> prepared_hulls(const RigidObject& object,
                                                    const PrincipalFrame& principal,
                                                    const BulletUnits& units,
                                                    const HullShapeOptions& options);

/// Default capacity of the hull cache, bytes (64 MiB; the 30 built-in objects at the drop's
/// defaults take about 5 MB).
inline constexpr std::size_t kDefaultHullCacheCapacity = std::size_t(64) << 20;

/// State of the hull cache.
struct HullCacheInfo {
  std::size_t entries = 0;
  std::size_t bytes = 0;     ///< estimated memory of the entries
  std::size_t capacity = 0;  ///< bytes; 0: nothing is cached
  std::int64_t hits = 0;     ///< preparations served from the cache (since the last clear)
  std::int64_t misses = 0;   ///< preparations made (since the last clear)
  std::int64_t evictions = 0;
};
HullCacheInfo hull_cache_info();
/// Drops every entry and resets the counters (the capacity stays).
void clear_hull_cache();
/// Sets the capacity (bytes; 0: cache nothing) and evicts down to it.
void set_hull_cache_capacity(std::size_t bytes);

}  // namespace mgn::physics
