// The bake cache (lodbake/bake/cache.h). Layout under the cache folder:
//   v2/deps/<primary key>.txt   side-file list: "lodbake-deps 1", then per input "input <i> <n>" and n paths
//   v2/packs/<result key>.bin   "lodbake-cache 2\n<summary bytes> <report bytes> <glb bytes> <payload hash>\n" + the
//                               three (the hash, 16 hex digits of Hasher over them, catches a garbled payload)
#include "lodbake/bake/cache.h"

#include <cstdio>
#include <filesystem>
#include <sstream>
#include <system_error>

#include "lodbake/core/file_io.h"
#include "lodbake/core/hash.h"
#include "lodbake/version.h"

namespace lodbake {

namespace {

namespace fs = std::filesystem;

constexpr const char* kLayout = "v2"; // v1: entries without a payload hash
constexpr const char* kDepsMagic = "lodbake-deps 1";
constexpr const char* kEntryMagic = "lodbake-cache 2";

// Two hashers seeded differently give a 128-bit key.
struct KeyHasher {
    Hasher a, b;
    KeyHasher() {
        a.addString("lodbake cache key a");
        b.addString("lodbake cache key b");
    }
    void bytes(const void* p, size_t n) {
        a.addBytes(p, n);
        b.addBytes(p, n);
    }
    void u64(uint64_t v) {
        a.addU64(v);
        b.addU64(v);
    }
    void str(const std::string& s) {
        a.addString(s);
        b.addString(s);
    }
    CacheKey key() const { return {a.digest(), b.digest()}; }
};

std::string depsPath(const std::string& dir, const CacheKey& k) {
    return joinPath(joinPath(joinPath(dir, kLayout), "deps"), k.hex() + ".txt");
}

std::string packPath(const std::string& dir, const CacheKey& k) {
    return joinPath(joinPath(joinPath(dir, kLayout), "packs"), k.hex() + ".bin");
}

// The side file as stored in the deps list: relative to the input's folder.
std::string relativeToInput(const std::string& input, const std::string& file) {
    const fs::path base = fs::path(parentDirectory(input)).lexically_normal();
    const fs::path rel = fs::path(file).lexically_normal().lexically_relative(base.empty() ? fs::path(".") : base);
    return rel.empty() ? file : rel.string();
}

std::string underInput(const std::string& input, const std::string& relative) {
    return fs::path(joinPath(parentDirectory(input), relative)).lexically_normal().string();
}

Result<CacheKey> resultKey(const CacheKey& primary, const std::vector<std::vector<std::string>>& side_relative,
                           const std::vector<std::string>& inputs) {
    KeyHasher h;
    h.u64(primary.hi);
    h.u64(primary.lo);
    for (size_t i = 0; i < side_relative.size(); ++i) {
        h.u64(side_relative[i].size());
        for (const std::string& rel : side_relative[i]) {
            LODBAKE_ASSIGN_OR_RETURN(std::vector<uint8_t> bytes, readFileBytes(underInput(inputs[i], rel)));
            h.str(rel);
            h.u64(bytes.size());
            h.bytes(bytes.data(), bytes.size());
        }
    }
    return h.key();
}

bool readDeps(const std::string& path, size_t input_count, std::vector<std::vector<std::string>>& out) {
    Result<std::vector<uint8_t>> bytes = readFileBytes(path, uint64_t(1) << 24);
    return bytes.ok() && parseCacheDeps(std::string(bytes->begin(), bytes->end()), input_count, out);
}

uint64_t payloadHash(const uint8_t* data, size_t size) {
    Hasher h;
    h.addString(kEntryMagic);
    h.addBytes(data, size);
    return h.digest();
}

Status makeDirs(const std::string& dir) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) return ioError(dir + ": cannot create cache folder: " + ec.message());
    return Status::okStatus();
}

} // namespace

bool parseCacheDeps(const std::string& text, size_t input_count, std::vector<std::vector<std::string>>& out) {
    std::istringstream in(text);
    std::string line;
    if (!std::getline(in, line) || line != kDepsMagic) return false;
    out.assign(input_count, {});
    for (size_t i = 0; i < input_count; ++i) {
        if (!std::getline(in, line)) return false;
        size_t index = 0, count = 0;
        char tail = 0;
        if (std::sscanf(line.c_str(), "input %zu %zu%c", &index, &count, &tail) != 2 || index != i) return false;
        for (size_t k = 0; k < count; ++k) {
            if (!std::getline(in, line) || line.empty() || line.find('\0') != std::string::npos) return false;
            out[i].push_back(line);
        }
    }
    return true;
}

bool parseCacheEntry(const std::vector<uint8_t>& bytes, CacheEntry& entry) {
    const std::string magic = std::string(kEntryMagic) + "\n";
    if (bytes.size() < magic.size() || std::string(bytes.begin(), bytes.begin() + long(magic.size())) != magic)
        return false;
    size_t pos = magic.size();
    size_t eol = pos;
    while (eol < bytes.size() && bytes[eol] != '\n' && eol - pos < 96) ++eol;
    if (eol >= bytes.size() || bytes[eol] != '\n') return false;
    const std::string sizes(bytes.begin() + long(pos), bytes.begin() + long(eol));
    unsigned long long s = 0, r = 0, g = 0;
    char hash[17] = {0};
    char tail = 0;
    // %16[0-9a-f] and the length check below: exactly 16 lowercase hex digits, nothing after them.
    if (std::sscanf(sizes.c_str(), "%llu %llu %llu %16[0-9a-f]%c", &s, &r, &g, hash, &tail) != 4 ||
        std::string(hash).size() != 16)
        return false;
    // sscanf also takes signs, leading zeros and extra blanks; only the line the writer makes is an
    // entry, so that an accepted entry is exactly what serializeCacheEntry would write.
    if (sizes != std::to_string(s) + " " + std::to_string(r) + " " + std::to_string(g) + " " + hash) return false;
    pos = eol + 1;
    const uint64_t rest = bytes.size() - pos;
    if (s > rest || r > rest - s || g != rest - s - r) return false;
    if (hashToHex(payloadHash(bytes.data() + pos, size_t(rest))) != hash) return false;
    entry.summary.assign(bytes.begin() + long(pos), bytes.begin() + long(pos + s));
    pos += s;
    entry.report_json.assign(bytes.begin() + long(pos), bytes.begin() + long(pos + r));
    pos += r;
    entry.glb.assign(bytes.begin() + long(pos), bytes.end());
    return true;
}

std::vector<uint8_t> serializeCacheEntry(const CacheEntry& entry) {
    std::vector<uint8_t> payload(entry.summary.begin(), entry.summary.end());
    payload.insert(payload.end(), entry.report_json.begin(), entry.report_json.end());
    payload.insert(payload.end(), entry.glb.begin(), entry.glb.end());
    const std::string head = std::string(kEntryMagic) + "\n" + std::to_string(entry.summary.size()) + " " +
                             std::to_string(entry.report_json.size()) + " " + std::to_string(entry.glb.size()) + " " +
                             hashToHex(payloadHash(payload.data(), payload.size())) + "\n";
    std::vector<uint8_t> blob(head.begin(), head.end());
    blob.insert(blob.end(), payload.begin(), payload.end());
    return blob;
}

std::string CacheKey::hex() const {
    return hashToHex(hi) + hashToHex(lo);
}

Result<CacheLookup> cacheLookup(const std::string& cache_dir, const std::vector<std::string>& inputs,
                                const std::vector<std::string>& names, const BakeSettings& settings) {
    CacheLookup lookup;
    KeyHasher h;
    h.str(kVersionString);
    BakeSettings keyed = settings;
    keyed.threads = 0; // neither changes the output bytes
    keyed.memory_limit_mib = 0;
    h.str(settingsToJson(keyed));
    h.u64(inputs.size());
    for (size_t i = 0; i < inputs.size(); ++i) {
        LODBAKE_ASSIGN_OR_RETURN(std::vector<uint8_t> bytes, readFileBytes(inputs[i]));
        h.str(i < names.size() ? names[i] : std::string());
        h.str(lowerExtension(inputs[i]));
        h.u64(bytes.size());
        h.bytes(bytes.data(), bytes.size());
    }
    lookup.primary = h.key();
    std::vector<std::vector<std::string>> side;
    if (!readDeps(depsPath(cache_dir, lookup.primary), inputs.size(), side)) return lookup;
    Result<CacheKey> key = resultKey(lookup.primary, side, inputs);
    if (!key.ok()) return lookup; // a side file went away: the bake will say what is missing
    Result<std::vector<uint8_t>> bytes = readFileBytes(packPath(cache_dir, *key));
    if (!bytes.ok() || !parseCacheEntry(*bytes, lookup.entry)) return lookup;
    lookup.hit = true;
    lookup.result = *key;
    lookup.files_read.resize(inputs.size());
    for (size_t i = 0; i < inputs.size(); ++i) {
        lookup.files_read[i].push_back(inputs[i]);
        for (const std::string& rel : side[i]) lookup.files_read[i].push_back(underInput(inputs[i], rel));
    }
    return lookup;
}

Status cacheStore(const std::string& cache_dir, const CacheKey& primary, const std::vector<std::string>& inputs,
                  const std::vector<std::vector<std::string>>& files_read, const CacheEntry& entry) {
    std::vector<std::vector<std::string>> side(inputs.size());
    std::string deps = std::string(kDepsMagic) + "\n";
    for (size_t i = 0; i < inputs.size(); ++i) {
        if (i < files_read.size())
            for (size_t k = 1; k < files_read[i].size(); ++k) {
                const std::string rel = relativeToInput(inputs[i], files_read[i][k]);
                if (rel.find('\n') != std::string::npos || rel.find('\r') != std::string::npos)
                    return invalidInput(files_read[i][k] + ": a path with a line break cannot be cached");
                side[i].push_back(rel);
            }
        deps += "input " + std::to_string(i) + " " + std::to_string(side[i].size()) + "\n";
        for (const std::string& rel : side[i]) deps += rel + "\n";
    }
    LODBAKE_ASSIGN_OR_RETURN(CacheKey key, resultKey(primary, side, inputs));
    const std::vector<uint8_t> blob = serializeCacheEntry(entry);
    const std::string pack = packPath(cache_dir, key);
    const std::string deps_file = depsPath(cache_dir, primary);
    LODBAKE_RETURN_IF_ERROR(makeDirs(parentDirectory(pack)));
    LODBAKE_RETURN_IF_ERROR(makeDirs(parentDirectory(deps_file)));
    // The pack first: a deps list that points at a missing pack is only a miss.
    LODBAKE_RETURN_IF_ERROR(writeFileAtomic(pack, blob.data(), blob.size()));
    return writeFileAtomic(deps_file, deps.data(), deps.size());
}

} // namespace lodbake
