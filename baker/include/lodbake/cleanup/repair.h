#pragma once
// The default repair pipeline: weld → degenerate/duplicate faces → unreferenced vertices → manifold
// → orientation → small components → holes → (denoise, off by default) → normals, each pass
// reporting what it changed, with validate() before and after.

#include <string>
#include <vector>

#include "lodbake/cleanup/denoise.h"
#include "lodbake/cleanup/normals.h"
#include "lodbake/cleanup/passes.h"
#include "lodbake/cleanup/validate.h"
#include "lodbake/core/diagnostics.h"
#include "lodbake/core/status.h"

namespace lodbake {

struct RepairOptions {
    bool weld = true;
    WeldOptions weld_options{1e-6}; // tiny tolerance: catches float noise in "shared" vertices of soups
    bool remove_degenerate = true;
    DegenerateOptions degenerate_options;
    bool make_manifold = true;
    ManifoldOptions manifold_options;
    bool orient = true;
    OrientOptions orient_options;
    bool remove_small_components = true;
    ComponentOptions component_options;
    bool fill_holes = true;
    HoleFillOptions hole_options;
    bool denoise = false; // changes geometry: opt in (see docs/repair.md)
    DenoiseOptions denoise_options;
    bool normals = true;
    NormalOptions normal_options;
    bool report_welded = true; // fill RepairReport::after_welded (one more validate() of the whole mesh)
    bool report_before = true; // fill RepairReport::before; when false the input is validated only if a
                               // pass's skip test needs it (no pass changed the mesh yet), and `before` stays empty
};

struct PassSummary {
    std::string name; // "weld", "degenerate", ...
    PassCounters counters;
    std::vector<std::string> notes;
};

struct RepairReport {
    ValidationReport before;             // left empty when RepairOptions::report_before is false
    ValidationReport after;
    ValidationReport after_welded;       // `after` with bit-identical positions merged: UV/normal seams are not rims
                                         // (left empty when RepairOptions::report_welded is false)
    std::vector<PassSummary> passes;
    std::vector<std::string> unresolved; // what the pipeline could not fix, one line each
};

/// Runs the enabled passes in the order above on `mesh`. Fails (InvalidInput) only when the mesh is
/// internally inconsistent (checkMeshConsistency); `name` prefixes that message. What remains wrong
/// afterwards is listed in RepairReport::unresolved and also sent to `diagnostics` as warnings:
/// non-manifold and orientation problems as stored, open rims and components with seams merged.
Result<RepairReport> repairMesh(Mesh& mesh, const RepairOptions& options, const std::string& name,
                                Diagnostics& diagnostics);

} // namespace lodbake
