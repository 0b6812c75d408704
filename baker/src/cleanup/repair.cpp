// The default repair pipeline (see repair.h and docs/repair.md).
#include "lodbake/cleanup/repair.h"

#include <algorithm>
#include <array>
#include <functional>
#include <string>

#include "core/parallel.h"
#include "mesh_edit.h"

namespace lodbake {

namespace {

// Lengths of the boundary loops that are not attribute seams (descending), and the face counts of
// the components with UV islands joined across seams (descending). `weld` is positionWeldMap(mesh).
// `table` is buildEdgeTable(mesh).
void openRimsAndSurfaces(const Mesh& mesh, const cleanup_detail::EdgeTable& table, const std::vector<uint32_t>& weld,
                         std::vector<uint32_t>& rims, std::vector<uint32_t>& surfaces) {
    using namespace cleanup_detail;
    const std::vector<uint8_t> seam = seamCorners(mesh, table, weld);
    for (const BoundaryLoop& loop : findBoundaryLoops(mesh, table))
        if (std::none_of(loop.corners.begin(), loop.corners.end(), [&](uint32_t c) { return seam[c] != 0; }))
            rims.push_back(uint32_t(loop.vertices.size()));
    UnionFind uf(mesh.vertexCount());
    for (uint32_t c = 0; c < seam.size(); ++c)
        if (seam[c]) {
            uf.unite(halfStart(mesh, c), weld[halfStart(mesh, c)]);
            uf.unite(halfEnd(mesh, c), weld[halfEnd(mesh, c)]);
        }
    for (FaceId f(0); f.value < mesh.faceCount(); ++f.value) {
        const std::array<VertexId, 3> t = mesh.triangle(f);
        uf.unite(t[0].value, t[1].value);
        uf.unite(t[0].value, t[2].value);
    }
    std::vector<uint32_t> faces_of_root(mesh.vertexCount(), 0);
    for (FaceId f(0); f.value < mesh.faceCount(); ++f.value) ++faces_of_root[uf.find(mesh.triangle(f)[0].value)];
    for (uint32_t count : faces_of_root)
        if (count) surfaces.push_back(count);
    std::sort(rims.begin(), rims.end(), std::greater<uint32_t>());
    std::sort(surfaces.begin(), surfaces.end(), std::greater<uint32_t>());
}

bool hasSharedPositions(const std::vector<uint32_t>& weld) {
    for (VertexId v(0); v.value < weld.size(); ++v.value)
        if (weld[v.value] != v.value) return true;
    return false;
}

std::string lengthsList(const std::vector<uint32_t>& lengths, size_t max_items = 10) {
    std::string s;
    for (size_t i = 0; i < lengths.size() && i < max_items; ++i) s += (i ? ", " : "") + std::to_string(lengths[i]);
    if (lengths.size() > max_items) s += ", ... (" + std::to_string(lengths.size()) + " in all)";
    return s;
}

// What the passes of one repairMesh call share: the report being built, the storage they hand on to
// each other, and what is known about the mesh still being the input.
//
// `before` is needed by the skip tests only while no pass has changed the mesh, so when the caller
// does not want it reported it is computed at the first such test, from the mesh as it still is then
// (same indices and positions as the input). `before` describes the mesh exactly until some pass
// changes its indices or positions, so a pass whose whole job that report shows to be empty is
// skipped (its counters are the zeros it would have reported). `same_faces` tracks that;
// `same_connectivity` also survives orientation flips, which change no adjacency.
struct RepairRun {
    Mesh& mesh;
    const RepairOptions& options;
    RepairReport report;
    cleanup_detail::Scratch scratch;
    ValidationReport unchanged_input;
    bool have_before = false;
    bool same_faces = true, same_connectivity = true;
    // The weld map of the final mesh, and whether scratch.table holds the final mesh's edge table.
    std::vector<uint32_t> weld;
    bool have_table = false;

    RepairRun(Mesh& m, const RepairOptions& o) : mesh(m), options(o) {
        if (options.report_before) {
            report.before = validate(mesh);
            have_before = true;
        }
    }
    const ValidationReport& before() const { return options.report_before ? report.before : unchanged_input; }
    const ValidationReport& inputReport() {
        if (!have_before) {
            unchanged_input = validate(mesh);
            have_before = true;
        }
        return before();
    }
    const TopologyStats& b() { return inputReport().topology; }
    PassSummary* add(const char* pass, PassCounters counters) {
        report.passes.push_back({pass, std::move(counters), {}});
        return &report.passes.back();
    }
    void changed(bool faces, bool connectivity) {
        same_faces = same_faces && !faces;
        same_connectivity = same_connectivity && !connectivity;
    }
};

// Weld, degenerate and unreferenced removal, manifold repair and orientation.
void repairConnectivity(RepairRun& run) {
    Mesh& mesh = run.mesh;
    const RepairOptions& options = run.options;
    if (options.weld) {
        const WeldReport w = weldVertices(mesh, options.weld_options);
        run.changed(w.vertices_merged != 0, w.vertices_merged != 0);
        run.add("weld", w.counters());
    }
    if (options.remove_degenerate) {
        DegenerateReport d;
        if (!run.same_faces || run.b().degenerate_face_count || run.b().duplicate_face_count ||
            run.b().non_finite_vertex_count)
            d = removeDegenerateFaces(mesh, options.degenerate_options);
        const bool removed = d.repeated_index_faces + d.zero_area_faces + d.duplicate_faces + d.non_finite_faces != 0;
        run.changed(removed, removed);
        run.add("degenerate", d.counters());
    }
    {
        const UnreferencedReport u = removeUnreferencedVertices(mesh);
        run.changed(u.vertices_removed != 0, u.vertices_removed != 0);
        run.add("unreferenced", u.counters());
    }
    if (options.make_manifold) {
        ManifoldReport m;
        if (!run.same_faces || run.b().non_manifold_edge_count || run.b().non_manifold_vertex_count ||
            run.b().degenerate_face_count)
            m = cleanup_detail::makeManifold(mesh, options.manifold_options, run.scratch);
        const bool edited = m.repeated_index_faces_removed + m.faces_cut + m.faces_removed + m.vertices_split != 0;
        run.changed(edited, edited);
        run.add("manifold", m.counters());
    }
    if (options.orient) {
        const OrientReport o = cleanup_detail::orientFaces(mesh, options.orient_options, run.scratch);
        run.changed(o.faces_flipped != 0 || o.vertices_added != 0, o.vertices_added != 0);
        run.add("orient", o.counters());
    }
}

// Small-component removal, hole filling and denoising.
void repairSurface(RepairRun& run) {
    Mesh& mesh = run.mesh;
    const RepairOptions& options = run.options;
    if (options.remove_small_components) {
        // The largest component always stays, so one component (as stored) means nothing to do.
        ComponentReport c;
        if (!run.same_connectivity || run.inputReport().component_face_counts.size() > 1)
            c = removeSmallComponents(mesh, options.component_options);
        else
            c.components_before = run.inputReport().component_face_counts.size();
        run.add("small_components", c.counters());
        UnreferencedReport u;
        if (c.faces_removed) u = removeUnreferencedVertices(mesh);
        run.report.passes.back().counters.push_back({"vertices_removed", u.vertices_removed});
        run.changed(c.faces_removed != 0, c.faces_removed != 0);
    }
    if (options.fill_holes) {
        HoleFillReport h;
        if (!run.same_connectivity || run.b().boundary_edge_count)
            h = cleanup_detail::fillHoles(mesh, options.hole_options, run.scratch);
        PassSummary* s = run.add("holes", h.counters());
        if (!h.filled_lengths.empty())
            s->notes.push_back("filled holes of " + lengthsList(h.filled_lengths) + " edges");
        if (!h.skipped_lengths.empty())
            s->notes.push_back("left open (over " + std::to_string(options.hole_options.max_hole_edges) +
                               " edges): " + lengthsList(h.skipped_lengths));
        run.changed(h.faces_added != 0, h.faces_added != 0);
    }
    if (options.denoise) {
        const DenoiseReport d = denoise(mesh, options.denoise_options);
        PassSummary* s = run.add("denoise", d.counters());
        s->notes.push_back("roughness (mean dihedral deviation) " + std::to_string(d.roughness_before_deg) + " -> " +
                           std::to_string(d.roughness_after_deg) + " degrees");
        run.changed(true, false); // positions move: zero-area faces may appear or vanish
    }
}

// The normals pass (the last one), then `after` and the final mesh's weld map (run.weld).
void computeNormalsAndAfter(RepairRun& run) {
    Mesh& mesh = run.mesh;
    const RepairOptions& options = run.options;
    RepairReport& report = run.report;
    // The final mesh's weld map, when the normals pass leaves one behind.
    std::vector<uint32_t> final_weld;
    bool have_final_weld = false;
    // The edge table of the final mesh, built once for `after` and reused for the open rims.
    cleanup_detail::EdgeTable& table = run.scratch.table;
    // `after` reads only faces and positions. Without creases the normals pass moves no position and
    // adds no vertex, so `after` is already the final mesh's and is computed beside that pass (each
    // task writes only its own results).
    const bool after_beside_normals = options.normals && !(options.normal_options.crease_angle_deg < 180.0) &&
                                      !(run.same_faces && run.have_before);
    if (options.normals) {
        NormalsReport n;
        if (after_beside_normals) {
            auto task = [&](size_t i) {
                if (i == 0)
                    n = cleanup_detail::computeNormals(mesh, options.normal_options, final_weld);
                else
                    report.after = cleanup_detail::validateWithTable(mesh, {}, &table);
            };
            if (!parallelFor(2, 1, task).ok()) { // a worker ran out of memory: both again on this thread
                task(0);
                task(1);
            }
            run.have_table = true;
        } else {
            n = cleanup_detail::computeNormals(mesh, options.normal_options, final_weld);
        }
        have_final_weld = n.vertices_added == 0; // no vertex added: positions and ids as the map saw them
        run.changed(n.vertices_added != 0, n.vertices_added != 0);
        run.add("normals", n.counters());
    }
    // The weld map of the final mesh, for the seam checks: built beside `after`'s counts.
    run.weld = std::move(final_weld);
    auto weldMap = [&] {
        if (!have_final_weld) run.weld = cleanup_detail::positionWeldMap(mesh);
    };
    if (after_beside_normals) {
        weldMap();
    } else if (run.same_faces && run.have_before) {
        report.after = run.before();
        weldMap();
    } else {
        run.have_table = true;
        report.after = cleanup_detail::validateWithTable(mesh, {}, &table, weldMap);
    }
}

// What the repair left unresolved, from `after` and, with attribute seams joined, the open rims and
// components; each also goes to `diagnostics` as a warning.
void listUnresolved(RepairRun& run, bool shared, const std::string& name, Diagnostics& diagnostics) {
    RepairReport& report = run.report;
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
    // Rims and components are judged with attribute seams joined: UV islands are not holes or pieces.
    std::vector<uint32_t> rims, surfaces;
    if (shared) {
        cleanup_detail::EdgeTable& table = run.scratch.table;
        if (!run.have_table) cleanup_detail::buildEdgeTable(run.mesh.indices, run.mesh.vertexCount(), table);
        openRimsAndSurfaces(run.mesh, table, run.weld, rims, surfaces);
    } else { // no two vertices share a position: no seams, so `after` already has both lists
        rims = report.after.boundary_loop_lengths;
        surfaces = report.after.component_face_counts;
    }
    if (!rims.empty())
        unresolved(std::to_string(rims.size()) + " boundary loops left open (" + lengthsList(rims) + " edges)");
    if (surfaces.size() > 1)
        unresolved(std::to_string(surfaces.size()) + " components remain (faces: " + lengthsList(surfaces, 5) +
                   "); separate pieces and overlapping sheets are not joined");
    if (t.degenerate_face_count) unresolved(std::to_string(t.degenerate_face_count) + " degenerate faces remain");
    if (t.duplicate_face_count) unresolved(std::to_string(t.duplicate_face_count) + " duplicate faces remain");
}

} // namespace

Result<RepairReport> repairMesh(Mesh& mesh, const RepairOptions& options, const std::string& name,
                                Diagnostics& diagnostics) {
    LODBAKE_RETURN_IF_ERROR(checkMeshConsistency(mesh, name));
    RepairRun run(mesh, options);
    repairConnectivity(run);
    repairSurface(run);
    computeNormalsAndAfter(run);
    const bool shared = hasSharedPositions(run.weld);
    // The welded report is information only (`unresolved` takes rims and components from
    // openRimsAndSurfaces), so callers that need just `unresolved` skip that validate() pass.
    if (options.report_welded) {
        if (shared) {
            ValidateOptions welded;
            welded.weld_by_position = true;
            run.report.after_welded = validate(mesh, welded);
        } else {
            run.report.after_welded = run.report.after; // nothing to weld
        }
    }
    listUnresolved(run, shared, name, diagnostics);
    return std::move(run.report);
}

} // namespace lodbake
