#pragma once
// The per-format halves of openMeshStream (lodbake/io/mesh_stream.h).
#include <memory>
#include <string>

#include "io/stream_window.h"
#include "lodbake/io/mesh_stream.h"

namespace lodbake::detail {

Result<std::unique_ptr<MeshStreamReader>> openPlyStream(std::unique_ptr<ByteSource> source, const std::string& name,
                                                        const StreamReadOptions& options, Diagnostics& diagnostics);
Result<std::unique_ptr<MeshStreamReader>> openObjStream(std::unique_ptr<ByteSource> source, const std::string& name,
                                                        const StreamReadOptions& options, Diagnostics& diagnostics);

} // namespace lodbake::detail
