// TRANSIENT: replaced by the OFF reader work before anything lands.
#include "lodbake/io/off.h"
namespace lodbake {
Result<LoadedMesh> readOffFromMemory(const uint8_t*, size_t, const std::string& name, const ReadOptions&, Diagnostics&) {
    return unsupported(name + ": OFF reader not built yet");
}
std::string writeOffToMemory(const Mesh&) { return {}; }
} // namespace lodbake
