// The default repair pipeline (see repair.h and docs/repair.md).
#include "lodbake/cleanup/repair.h"

#include <string>

namespace lodbake {

namespace {

std::string lengthsList(const std::vector<uint32_t>& lengths, size_t max_items = 10) {
    std::string s;
    for (size_t i = 0; i < lengths.size() && i < max_items; ++i) s += (i ? ", " : "") + std::to_string(lengths[i]);
    if (lengths.size() > max_items) s += ", ... (" + std::to_string(lengths.size()) + " in all)";
    return s;
}

} // namespace

Result<RepairReport> repairMesh(Mesh& mesh, const RepairOptions& options, const std::string& name,
                                Diagnostics& diagnostics) {
    LODBAKE_RETURN_IF_ERROR(checkMeshConsistency(mesh, name));
    RepairReport report;
    report.before = validate(mesh);
    auto add = [&](const char* pass, PassCounters counters) {
        report.passes.push_back({pass, std::move(counters), {}});
        return &report.passes.back();
    };
    if (options.weld) add("weld", weldVertices(mesh, options.weld_options).counters());
    if (options.remove_degenerate)
        add("degenerate", removeDegenerateFaces(mesh, options.degenerate_options).counters());
    add("unreferenced", removeUnreferencedVertices(mesh).counters());
    if (options.make_manifold) add("manifold", makeManifold(mesh, options.manifold_options).counters());
    if (options.orient) add("orient", orientFaces(mesh, options.orient_options).counters());
    if (options.remove_small_components) {
        add("small_components", removeSmallComponents(mesh, options.component_options).counters());
        const UnreferencedReport u = removeUnreferencedVertices(mesh);
        report.passes.back().counters.push_back({"vertices_removed", u.vertices_removed});
    }
    if (options.fill_holes) {
        const HoleFillReport h = fillHoles(mesh, options.hole_options);
        PassSummary* s = add("holes", h.counters());
        if (!h.filled_lengths.empty())
            s->notes.push_back("filled holes of " + lengthsList(h.filled_lengths) + " edges");
        if (!h.skipped_lengths.empty())
            s->notes.push_back("left open (over " + std::to_string(options.hole_options.max_hole_edges) +
                               " edges): " + lengthsList(h.skipped_lengths));
    }
    if (options.denoise) {
        const DenoiseReport d = denoise(mesh, options.denoise_options);
        PassSummary* s = add("denoise", d.counters());
        s->notes.push_back("roughness (mean dihedral deviation) " + std::to_string(d.roughness_before_deg) + " -> " +
                           std::to_string(d.roughness_after_deg) + " degrees");
    }
    if (options.normals) add("normals", computeNormals(mesh, options.normal_options).counters());
    report.after = validate(mesh);
    ValidateOptions welded;
    welded.weld_by_position = true;
    report.after_welded = validate(mesh, welded);

    const TopologyStats& t = report.after.topology;
    auto unresolved = [&](const std::string& what) {
        report.unresolved.push_back(what);
        diagnostics.warn(name + ": repair: " + what);
    };
    if (t.face_count == 0) unresolved("no triangles left");
    if (t.non_manifold_edge_count) unresolved(std::to_string(t.non_manifold_edge_count) + " non-manifold edges remain");
    if (t.non_manifold_vertex_count)
        unresolved(std::to_string(t.non_manifold_vertex_count) + " non-manifold vertices remain");
    if (t.inconsistent_edge_count)
        unresolved(std::to_string(t.inconsistent_edge_count) + " edges with inconsistent orientation remain");
    // Rims and components are judged with seams merged: UV islands are not holes or pieces.
    const ValidationReport& w = report.after_welded;
    if (!w.boundary_loop_lengths.empty())
        unresolved(std::to_string(w.boundary_loop_lengths.size()) + " boundary loops left open (" +
                   lengthsList(w.boundary_loop_lengths) + " edges)");
    if (w.component_face_counts.size() > 1)
        unresolved(std::to_string(w.component_face_counts.size()) + " components remain (faces: " +
                   lengthsList(w.component_face_counts, 5) + "); overlapping sheets are not merged");
    if (t.degenerate_face_count) unresolved(std::to_string(t.degenerate_face_count) + " degenerate faces remain");
    if (t.duplicate_face_count) unresolved(std::to_string(t.duplicate_face_count) + " duplicate faces remain");
    return report;
}

} // namespace lodbake
