#pragma once
// The content-hash bake cache (`--cache-dir DIR`). A pack is reused when the bytes of every file its
// bake would read, the resolved settings and the baker version are unchanged.
//
// Two steps, so that a hit never parses a mesh (ccache's "direct mode" in spirit):
//  1. The primary key hashes the baker version, the settings (threads excluded: they never change
//     the output), and per input its group name, extension and bytes. Under it the cache keeps the
//     list of side files (MTL, textures, .bin buffers, .conf scans) that bake read, relative to the
//     input's folder.
//  2. The result key hashes the primary key and the bytes of each listed side file. Under it the
//     cache keeps the pack, its report and its summary in one file.
// Because the side files are chosen by the bytes of the files that name them, and all of those are
// in the key, a stale list can only cause a miss, never a wrong hit. Every cache file is written
// with AtomicFileWriter (a temporary plus rename), so concurrent bakers sharing a folder never see
// a partial entry; two bakers storing the same key write the same bytes. Keys are 128-bit
// non-cryptographic hashes: fine against accidents, not against someone planting colliding inputs.

#include <cstdint>
#include <string>
#include <vector>

#include "lodbake/config/bake_config.h"
#include "lodbake/core/status.h"

namespace lodbake {

struct CacheKey {
    uint64_t hi = 0;
    uint64_t lo = 0;
    std::string hex() const; // 32 lowercase hex digits
};

/// What the cache holds for one pack.
struct CacheEntry {
    std::vector<uint8_t> glb;
    std::string report_json; // bakeReportJson of the pack
    std::string summary;     // bakeSummaryText of the pack
};

struct CacheLookup {
    bool hit = false;
    CacheKey primary;
    CacheEntry entry;                                 // valid when hit
    CacheKey result;                                  // when hit: the key the entry is stored under
    std::vector<std::vector<std::string>> files_read; // when hit: per input, the input then its side files
};

/// Step 1 and 2 for a bake of `inputs` (group names `names`, same length) with `settings`, in cache
/// folder `cache_dir`. A miss (nothing stored, a listed side file gone or changed, a damaged entry)
/// is not an error; failing to read an input is.
Result<CacheLookup> cacheLookup(const std::string& cache_dir, const std::vector<std::string>& inputs,
                                const std::vector<std::string>& names, const BakeSettings& settings);

/// Stores `entry` for the bake whose primary key is `primary` (from cacheLookup) and which read
/// `files_read[i]` for input i (the input itself first, as SourceInfo::files_read lists them).
/// Creates the folders it needs. Fails on IO errors (callers treat that as a warning).
Status cacheStore(const std::string& cache_dir, const CacheKey& primary, const std::vector<std::string>& inputs,
                  const std::vector<std::vector<std::string>>& files_read, const CacheEntry& entry);

/// The cache's file formats, exposed for tests and the fuzz target (tests/fuzz/fuzz_cache.cpp).
/// A damaged file is a miss, never an error: these return false for anything but a well-formed file.
/// Entries carry a hash of their payload, so a garbled (not only a truncated) entry is a miss too.
bool parseCacheEntry(const std::vector<uint8_t>& bytes, CacheEntry& entry);
std::vector<uint8_t> serializeCacheEntry(const CacheEntry& entry);
/// The side-file list under a primary key, for `input_count` inputs.
bool parseCacheDeps(const std::string& text, size_t input_count, std::vector<std::vector<std::string>>& out);

} // namespace lodbake
