// TRANSIENT: replaced by the OBJ reader work before anything lands.
#include "lodbake/io/obj.h"
namespace lodbake {
Result<LoadedMesh> readObjFromMemory(const uint8_t*, size_t, const std::string& name, const SideFileLoader&,
                                     const ReadOptions&, Diagnostics&) {
    return unsupported(name + ": OBJ reader not built yet");
}
ObjFiles writeObjToMemory(const Mesh&, const std::string&) { return {}; }
} // namespace lodbake
