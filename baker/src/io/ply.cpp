// TRANSIENT: replaced by the PLY reader work before anything lands.
#include "lodbake/io/ply.h"
namespace lodbake {
Result<LoadedMesh> readPlyFromMemory(const uint8_t*, size_t, const std::string& name, const ReadOptions&, Diagnostics&) {
    return unsupported(name + ": PLY reader not built yet");
}
std::vector<uint8_t> writePlyToMemory(const Mesh&, bool) { return {}; }
} // namespace lodbake
