#pragma once
// Streams: the extensions that encoders add to the levels of a baked asset (LODBAKE_valence_compression
// on each primitive, LODBAKE_progressive_fans on LOD0's mesh), as plug-ins. A stream is one
// PackStreamEncoder: what it needs (StreamNeeds), what it costs (StreamCost) and what it writes (the
// PackExtension its commit attaches). It is registered with one line in stream_registry.cpp; the bake
// reads only the PackStreamEncoder and needs no list of names.

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "lodbake/core/mesh.h"
#include "lodbake/core/status.h"
#include "lodbake/pack/pack.h"
#include "lodbake/pfrep/pfrep_region.h"
#include "lodbake/simplify/lod_chain.h"

namespace lodbake {

/// Writes a prepared stream into its level (attaches the extension; may renumber the level's mesh).
/// Empty when the encoder has nothing to add to that level.
using PackStreamCommit = std::function<Status(PackLevel& level)>;

/// What a stream reads besides the level it codes, which decides where the bake runs it.
struct StreamNeeds {
    /// Codes LOD0 alone (a structure of the whole mesh, such as a progressive representation): its
    /// prepare runs once, on LOD0, first among the asset's tasks; the other levels are not asked.
    bool lod0_only = false;
    /// Reads the chain's collapse record (LodChain::removals; the chain then records it).
    bool collapse_record = false;
    /// Reads the measured errors of chain.levels: the prepare steps of the levels after LOD0 run after
    /// the measurement (LOD0's prepare still runs beside it).
    bool measured_errors = false;
};

/// What a stream's prepare costs, for the scheduler that decides which tasks share a phase (a cut
/// that changes no byte, only the peak memory).
struct StreamCost {
    /// Working memory of one prepare, in bytes per triangle of the mesh it reads: what it holds above
    /// the bake's own data at its peak (tables, a check's decoder, a simplifier of its own).
    double bytes_per_triangle = 0;
};

/// A stream: an extension that an encoder adds to levels of an asset, registered once in
/// builtinStreamEncoders (stream_registry.cpp). The bake reads only this description: it needs no
/// list of names.
///
/// Two steps, so that the costly one can run while other stages still read the meshes: `prepare`
/// only reads `mesh` (the level as baked, before any encoder's commit; it must stay unchanged until
/// prepare returns) and does all the coding; the commit it returns is cheap and runs later, one
/// level and one encoder at a time, in encoder order, while `chain` is still alive. Between the two
/// the bake may drop dead levels from `chain` (docs/bake.md, "Dead levels"): their commits never run,
/// and a commit that lists the levels (LOD0's PFRep) reads the kept ones from `chain` then.
struct PackStreamEncoder {
    std::string extension_name;
    StreamNeeds needs;
    StreamCost cost;
    std::function<Result<PackStreamCommit>(const LodChain& chain, size_t level_index, const Mesh& mesh)> prepare;
};

/// An encoder of `extension_name` with its needs, cost and prepare step.
PackStreamEncoder makeStreamEncoder(
    std::string extension_name, StreamNeeds needs, StreamCost cost,
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
    uint32_t uv_bits = 12;       // UV sets, colours and tangents (codec::ValenceEncodeOptions), 4..16
    uint32_t color_bits = 8;
    uint32_t tangent_bits = 10;
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
    uint32_t uv_bits = 12; // the attributes keep the options' bits on every level
    uint32_t color_bits = 8;
    uint32_t tangent_bits = 10;
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

/// A level as its LODBAKE_valence_compression stream decodes (the bytes valenceStreamEncoder writes
/// for it with `options`): the decoded mesh and where each input vertex went. No value for a level
/// with several primitives (each coded apart). LOD0's format 4 PFRep blob is coded against it.
struct DecodedLevelStream {
    Mesh mesh;
    std::vector<uint32_t> new_vertex_of; // input vertex -> decoded vertex
};
Result<std::optional<DecodedLevelStream>> decodedLevelStream(const ValenceStreamOptions& options, const LodChain& chain,
                                                             size_t level_index, const Mesh& mesh);

/// What the bake's settings say about the streams (BakeSettings: stream precision, progressive_fans,
/// pfrep_from_chain).
struct StreamSettings {
    ValenceStreamOptions valence;
    bool progressive_fans = true; // LODBAKE_progressive_fans on LOD0
    bool pfrep_from_chain = false; // ... built from the chain's own collapses (StreamNeeds::collapse_record)
    uint32_t pfrep_format = 4;     // ... written as format 4 (against LOD0's stream), 3 (range-coded), 2 or 5
                                   // (region blocks; docs/format/pfrep.md)
    PfrepRegionOptions pfrep_regions; // ... format 5: its block sizes and the views they are cut for
    bool cluster_lod = false;      // LODBAKE_cluster_lod on LOD0 (grid bits: valence.position_bits)
};

/// The stream encoders built into this baker that `settings` enable, in the order they run (valence
/// last: it renumbers the level's vertices).
std::vector<PackStreamEncoder> builtinStreamEncoders(const StreamSettings& settings = {});

} // namespace lodbake
