#include "lodbake/bake/memory_budget.h"

#include <unistd.h>

#include <algorithm>
#include <set>

#include "lodbake/image/texture_resize.h"
#include "lodbake/io/mesh_stream.h"

namespace lodbake {

namespace {

uint64_t mib(uint64_t bytes) { return (bytes + (uint64_t(1) << 20) - 1) >> 20; }

} // namespace

uint64_t bakeMemoryAllowance(const BakeFootprint& footprint) {
    return kBakeBaseBytes + kBakeBytesPerTriangle * footprint.triangles + kBakeBytesPerTexel * footprint.texels;
}

uint64_t defaultBakeMemoryLimit() {
    const long pages = sysconf(_SC_PHYS_PAGES);
    const long page_bytes = sysconf(_SC_PAGESIZE);
    if (pages <= 0 || page_bytes <= 0) return uint64_t(4) << 30;
    return uint64_t(pages) * uint64_t(page_bytes) / 2;
}

Result<BakeFootprint> peekInputFootprint(const std::string& path, const ReadOptions& read, Diagnostics& diagnostics) {
    const MeshFormat format = formatFromPath(path);
    if (format != MeshFormat::Ply && format != MeshFormat::Obj) return BakeFootprint{};
    StreamReadOptions options;
    options.max_polygon_vertices = read.max_polygon_vertices;
    Result<std::unique_ptr<MeshStreamReader>> opened = openMeshStream(path, options, diagnostics);
    // PLY triangle strips and range grids are triangulated from positions: sized once loaded. Any
    // other reading error is the input's, reported as the in-memory reader would.
    if (!opened.ok()) {
        if (opened.status().code() == StatusCode::Unsupported) return BakeFootprint{};
        return opened.status();
    }
    MeshStreamReader& reader = **opened;
    if (format == MeshFormat::Obj) // the vertex pass counts the faces' triangles as it checks them
        LODBAKE_RETURN_IF_ERROR(reader.forEachVertexChunk([](uint64_t, const Vec3f*, size_t) { return Status(); }));
    BakeFootprint footprint;
    footprint.triangles = reader.info().triangle_estimate;
    footprint.known = true;
    return footprint;
}

BakeFootprint loadedFootprint(const std::vector<const Mesh*>& meshes) {
    BakeFootprint footprint;
    footprint.known = true;
    std::set<const Texture*> seen;
    for (const Mesh* mesh : meshes) {
        footprint.triangles += mesh->indices.size() / 3;
        for (const Texture& texture : mesh->textures) {
            if (!seen.insert(&texture).second || texture.bytes.empty()) continue;
            Result<ImageSize> size = probeImageSize(texture.bytes, texture.uri);
            if (size.ok()) footprint.texels += uint64_t(size->width) * size->height;
        }
    }
    return footprint;
}

Status bakeOverLimit(const std::string& what, const BakeFootprint& footprint, uint64_t limit) {
    return resourceLimit(what + ": the in-memory bake of " + std::to_string(footprint.triangles) + " triangles and " +
                         std::to_string(footprint.texels) + " texels is allowed " +
                         std::to_string(mib(bakeMemoryAllowance(footprint))) + " MiB, above the memory limit of " +
                         std::to_string(mib(limit)) + " MiB (--memory-limit)");
}

} // namespace lodbake
