// TRANSIENT: replaced by the glTF work before anything lands.
#include "lodbake/gltf/gltf_io.h"
namespace lodbake {
Result<LoadedMesh> readGltfFromMemory(const uint8_t*, size_t, const std::string& name, const SideFileLoader&,
                                      const ReadOptions&, Diagnostics&) {
    return unsupported(name + ": glTF reader not built yet");
}
Result<GltfFiles> writeGltfToMemory(const Mesh&, const GltfWriteOptions&) { return unsupported("glTF writer not built yet"); }
} // namespace lodbake
