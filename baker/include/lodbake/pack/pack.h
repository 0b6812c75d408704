#pragma once
// The pack description: what goes into a baked glTF pack, independent of any glTF library.
// writePackGlb (pack_glb.h) serialises it.
//
// Layout: one LOD group per baked asset. The group's LOD0 node is in the scene and carries MSFT_lod
// (ids of the lower-detail nodes, highest detail first), extras.MSFT_screencoverage and the
// LODBAKE_lod_metrics extension. Every level is an ordinary glTF mesh, so viewers without our
// extensions show LOD0.
//
// Extension hook: a compressed stream (LODBAKE_valence_compression on a primitive,
// LODBAKE_progressive_fans on a mesh) is a PackExtension added to a PackLevel by a
// PackStreamEncoder: its JSON object plus binary blobs that the writer stores as buffer views,
// writing each view's index into the named member of the object.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "lodbake/core/mesh.h"
#include "lodbake/core/status.h"
#include "lodbake/simplify/lod_chain.h"

namespace lodbake {

struct PackExtension {
    std::string name;                           // e.g. "LODBAKE_lod_metrics"
    std::string json;                           // the extension object as JSON text
    std::vector<std::vector<uint8_t>> blobs;    // payloads, each stored in its own buffer view
    std::vector<std::string> blob_view_members; // blob i's buffer-view index goes into this member
    bool is_stream = false;                     // a compressed stream: listed in extensionsRequired when compact
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
};

struct PackAsset {
    std::string name;
    std::vector<PackLevel> levels;              // highest detail first
    std::vector<double> screen_coverage;        // MSFT_screencoverage, one per level
    std::vector<PackExtension> node_extensions; // on the LOD0 node
};

struct PackDescription {
    std::vector<PackAsset> assets;
    bool compact = false; // stream extensions go into extensionsRequired
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
    std::vector<LodMetricsLevel> levels;
};

/// Metrics of `chain` with LOD0 = `full` (error 0, switch distance 0) prepended. `hysteresis` is the
/// band half-width as a fraction of each switch distance.
LodMetrics lodMetrics(const Mesh& full, const LodChain& chain, const ScreenParams& screen, double hysteresis);

/// The LODBAKE_lod_metrics extension object (sorted keys, shortest round-trip numbers).
PackExtension lodMetricsExtension(const LodMetrics& metrics);

/// MSFT_screencoverage values: level i is shown while the coverage is at least value i, i.e. until
/// level i+1's switch distance; the last level's value is 0 (never culled). Non-increasing.
std::vector<double> msftScreenCoverage(const LodMetrics& metrics);

/// Writes a prepared stream into its level (attaches the extension; may renumber the level's mesh).
/// Empty when the encoder has nothing to add to that level.
using PackStreamCommit = std::function<Status(PackLevel& level)>;

/// A compressed-stream encoder: adds its extension to level `level_index` of an asset.
///
/// Two steps, so that the costly one can run while other stages still read the meshes: `prepare`
/// only reads `mesh` (the level as baked, before any encoder's commit; it must stay unchanged until
/// prepare returns) and does all the coding; the commit it returns is cheap and runs later, one
/// level and one encoder at a time, in encoder order.
struct PackStreamEncoder {
    std::string extension_name;
    /// Reads the measured errors of chain.levels: the prepare steps of the levels after LOD0 run after
    /// the measurement (LOD0's prepare still runs beside it).
    bool needs_measurement = false;
    std::function<Result<PackStreamCommit>(const LodChain& chain, size_t level_index, const Mesh& mesh)> prepare;
};

/// An encoder named `extension_name` that codes with `prepare`.
PackStreamEncoder makeStreamEncoder(
    std::string extension_name,
    std::function<Result<PackStreamCommit>(const LodChain& chain, size_t level_index, const Mesh& mesh)> prepare);

/// Quantization of the LODBAKE_valence_compression streams. The defaults match gltfpack's default
/// quantization (14-bit positions, 8-bit normals), so pack sizes compare like for like.
///
/// Adaptive precision (`adaptive`): LOD0 keeps these bits; every other level whose error was measured
/// (chain.levels[l - 1].has_distance) gets the fewest position bits whose quantization moves no vertex
/// by more than `error_fraction` of the level's own measured mean distance e to LOD0, and the fewest
/// normal bits whose octahedral quantization turns no normal by more than `error_fraction` of
/// atan(e / L), L the level's median edge length (how far its faces already lean against LOD0's).
/// Never more than the bits above, never fewer than the format's minimum.
struct ValenceStreamOptions {
    uint32_t position_bits = 14; // 8..16, per coordinate in the bounding cube
    uint32_t normal_bits = 8;    // octahedral bits per component, 4..16
    bool adaptive = false;
    double error_fraction = 0.25; // (0, 1]: largest quantization displacement / the level's mean error
    /// Called between coding a primitive and decoding it for the check, when the coder's working set
    /// has been freed (BakeHooks::release_memory); optional, changes no byte.
    std::function<void()> release_memory;
};

/// The precision one level is coded with, and why.
struct ValencePrecision {
    uint32_t position_bits = 14;
    uint32_t normal_bits = 8;
    double max_displacement = 0; // largest distance quantization can move a vertex: sqrt(3)/2 * step
    double max_normal_angle = 0; // largest angle (radians) the normal quantization can turn a unit normal
};

/// Largest angle (radians) between a unit normal and its octahedral quantization with `bits` bits per
/// component, as the codec quantizes (round to nearest), measured once on a dense set of directions
/// and cached per bit depth.
double octahedralMaxAngle(uint32_t bits);

/// The precision `options` give level `level_index` of a chain whose mesh is `mesh` (its measured
/// errors in chain.levels[level_index - 1]). Without adaptive precision, for LOD0, or for a level
/// without a measured error: options' bits.
ValencePrecision valencePrecision(const ValenceStreamOptions& options, const LodChain& chain, size_t level_index,
                                  const Mesh& mesh);

/// The LODBAKE_valence_compression encoder (schemas/LODBAKE_valence_compression): codes each primitive
/// (non-empty sub-mesh) of a level with codec::encodeValence into its own buffer view, at the
/// precision valencePrecision gives the level, and reorders the level into the decoded order, so the
/// plain accessors and the decoded streams hold the same triangles with the same indices (uncoded
/// attributes such as UVs stay plain and line up with the decoded vertices). A level with one
/// primitive keeps all its vertices; a level with several is laid out primitive by primitive, each
/// primitive's vertices a range of its own (PackLevel::primitive_vertex_ranges; vertices two
/// primitives shared are copied, unreferenced ones dropped). Fails when the codec rejects the mesh or
/// when the decoded triangles are not the input's (an internal error).
PackStreamEncoder valenceStreamEncoder(const ValenceStreamOptions& options = {});

/// The stream encoders built into this baker, in the order they run (valence last: it renumbers the
/// level's vertices).
std::vector<PackStreamEncoder> builtinStreamEncoders(const ValenceStreamOptions& valence = {});

/// Compact packs need compressed streams: fails (Unsupported) naming the stream extensions that are
/// missing when `description.compact` is set and no stream extension is present.
Status checkCompact(const PackDescription& description);

} // namespace lodbake
