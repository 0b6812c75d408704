#include "lodbake/io/mesh_stream.h"

#include "io/ply_stream.h"
#include "lodbake/core/file_io.h"

namespace lodbake {

namespace {

Result<std::unique_ptr<MeshStreamReader>> openFormat(std::unique_ptr<detail::ByteSource> source,
                                                     const std::string& name, MeshFormat format,
                                                     const StreamReadOptions& options, Diagnostics& diagnostics) {
    if (format == MeshFormat::Ply) return detail::openPlyStream(std::move(source), name, options, diagnostics);
    if (format == MeshFormat::Obj) return detail::openObjStream(std::move(source), name, options, diagnostics);
    return unsupported(name + ": the streaming reader reads .ply and .obj files, not " + formatName(format));
}

} // namespace

Result<std::unique_ptr<MeshStreamReader>> openMeshStream(const std::string& path, const StreamReadOptions& options,
                                                         Diagnostics& diagnostics) {
    const MeshFormat format = formatFromPath(path);
    if (format != MeshFormat::Ply && format != MeshFormat::Obj)
        return unsupported(path + ": the streaming reader reads .ply and .obj files, got \"" + lowerExtension(path) +
                           "\"");
    auto source = std::make_unique<detail::ByteSource>();
    LODBAKE_RETURN_IF_ERROR(source->openFile(path));
    return openFormat(std::move(source), path, format, options, diagnostics);
}

Result<std::unique_ptr<MeshStreamReader>> openMeshStreamFromMemory(const uint8_t* data, size_t size,
                                                                   const std::string& name, MeshFormat format,
                                                                   const StreamReadOptions& options,
                                                                   Diagnostics& diagnostics) {
    auto source = std::make_unique<detail::ByteSource>();
    source->openMemory(data, size);
    return openFormat(std::move(source), name, format, options, diagnostics);
}

} // namespace lodbake
