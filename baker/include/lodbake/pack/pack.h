#pragma once
// The pack description: what goes into a baked glTF pack, independent of any glTF library.
// writePackGlb (pack_glb.h) serialises it.
//
// Layout: one LOD group per baked asset (or, with a PackScene, per node that names an asset). The
// group's LOD0 node is in the scene and carries MSFT_lod (ids of the lower-detail nodes, highest
// detail first), extras.MSFT_screencoverage and the LODBAKE_lod_metrics extension. Every level is an
// ordinary glTF mesh, so viewers without our extensions show LOD0.
//
// Extensions are structured data (PackExtension: a JsonNode object plus binary blobs that the writer
// stores as buffer views, writing each view's index into the named member of the object), added by
// the bake and by the streams (lodbake/stream/stream.h). This module depends on core only.

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "lodbake/core/json_value.h"
#include "lodbake/core/mesh.h"
#include "lodbake/core/status.h"

namespace lodbake {

class SpillFile; // lodbake/core/spill_file.h

struct PackExtension {
    std::string name;                           // e.g. lodrt::format::kExtLodMetrics
    JsonNode json;                              // the extension object
    std::vector<std::vector<uint8_t>> blobs;    // payloads, each stored in its own buffer view
    std::vector<std::string> blob_view_members; // blob i's buffer-view index goes into this member
    bool is_stream = false;                     // a compressed stream: listed in extensionsRequired when compact
    /// Empty, or one per blob: blob i is held by file spilled[i] (all its bytes, finished) instead of
    /// blobs[i], which stays empty. Only writePackGlbFile writes such an extension.
    std::vector<std::shared_ptr<const SpillFile>> spilled;
};

struct PackLevel {
    Mesh mesh;
    std::vector<PackExtension> mesh_extensions;
    std::vector<std::vector<PackExtension>> primitive_extensions; // per non-empty sub-mesh (glTF primitive), or empty
    /// Empty: the primitives share all of the mesh's vertices (one accessor per attribute). Else one
    /// range per non-empty sub-mesh: primitive p uses only vertices [first, first + count) and the
    /// writer gives it accessors over that range (its indices relative to `first`).
    struct VertexRange {
        uint32_t first = 0;
        uint32_t count = 0;
    };
    std::vector<VertexRange> primitive_vertex_ranges;
    /// --web: the coarsest position grid step the level accepts (0: the default grid only).
    double web_position_step = 0;
};

struct PackAsset {
    std::string name;
    std::vector<PackLevel> levels;              // highest detail first
    std::vector<double> screen_coverage;        // MSFT_screencoverage, one per level
    std::vector<PackExtension> node_extensions; // on the LOD0 node
};

/// A node of a kept scene graph. A node with an asset is that asset's LOD group: it holds LOD0 and
/// MSFT_lod, and the asset's lower levels get nodes of their own outside the scene (placed by this
/// node's world transform). Several nodes may name one asset (instancing: the meshes are shared).
struct PackNode {
    std::string name;
    bool name_from_asset = false;    // take the asset's name (an input baked without a graph)
    std::vector<double> matrix;      // the local transform as the input wrote it: 16 numbers, or
    std::vector<double> translation; // any of translation (3), rotation (4, x y z w), scale (3)
    std::vector<double> rotation;
    std::vector<double> scale;
    std::array<double, 16> world{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}; // column-major
    std::vector<uint32_t> children; // indices into PackScene::nodes
    int32_t asset = -1;             // index into PackDescription::assets, -1 for none
};

/// The node hierarchy a pack keeps (docs/bake.md "Scenes"). Empty: one root node per asset.
struct PackScene {
    std::vector<PackNode> nodes;
    std::vector<uint32_t> roots;
    bool empty() const { return nodes.empty(); }
};

struct PackDescription {
    std::vector<PackAsset> assets;
    PackScene scene; // empty: one LOD group node per asset in the scene
    bool compact = false; // stream extensions go into extensionsRequired
    bool web = false;     // levels quantized and EXT_meshopt_compression-compressed (docs/format/web.md)
};

/// Per-level metrics in the form LODBAKE_lod_metrics stores (schemas/LODBAKE_lod_metrics).
struct LodMetricsLevel {
    uint64_t triangles = 0;
    uint64_t vertices = 0;
    double hausdorff_error = 0;     // object units
    double mean_error = 0;          // object units
    double hausdorff_error_rel = 0; // fraction of the bounding-box diagonal
    double mean_error_rel = 0;
    double switch_distance = 0; // object units, from here on the level is acceptable
    double screen_coverage = 0; // projected bounding-sphere diameter / viewport height at the switch distance
    double hysteresis_near = 0; // switch back to the finer level below this distance
    double hysteresis_far = 0;  // switch to this level beyond this distance
};

struct LodMetrics {
    double bounding_radius = 0;
    double pixel_threshold = 1;
    double viewport_height_px = 1080;
    double vertical_fov_rad = 0;
    /// The input's triangles when the chain starts below it (an out-of-core bake: levels[0] is a cut
    /// of the cluster hierarchy, not the input): written as inputTriangles; 0, the default, writes
    /// nothing (levels[0] is the input).
    uint64_t input_triangles = 0;
    std::vector<LodMetricsLevel> levels;
};

/// The LODBAKE_lod_metrics extension object (sorted keys, shortest round-trip numbers).
PackExtension lodMetricsExtension(const LodMetrics& metrics);

/// MSFT_screencoverage values: level i is shown while the coverage is at least value i, i.e. until
/// level i+1's switch distance; the last level's value is 0 (never culled). Non-increasing.
std::vector<double> msftScreenCoverage(const LodMetrics& metrics);

/// Compact packs need compressed streams: fails (Unsupported) naming the stream extensions that are
/// missing when `description.compact` is set and no stream extension is present.
Status checkCompact(const PackDescription& description);

} // namespace lodbake
