#pragma once
// Stanford range-scan alignment files (.conf): a list of range scans and the rigid transform that
// places each in world coordinates. Reading one loads every scan, transforms it and concatenates
// them, so a whole turntable of scans bakes as one input (overlapping sheets, no welding between
// scans).
//
// Lines: "bmesh FILE tx ty tz qx qy qz qw" (a scan, FILE relative to the .conf's folder),
// "camera ..." and "mesh ..." (ignored; "mesh" names a scanner calibration object, noted in the
// diagnostics). A point p of FILE goes to R(q)^T · p + t, the Stanford convention (the conjugate
// quaternion), which puts the shared Stanford range scans onto their reconstructions.

#include <string>

#include "lodbake/io/mesh_io.h"

namespace lodbake {

/// Loads every bmesh of the .conf at `path` with readMesh(), transformed to world coordinates and
/// appended in file order. Errors name the .conf, the line and the scan.
Result<LoadedMesh> readConf(const std::string& path, const ReadOptions& options, Diagnostics& diagnostics);

/// Applies p' = R(q)^T · p + t to positions (and R(q)^T to normals and tangents) in place.
/// `q` is (x, y, z, w); it is normalised first.
void applyConfTransform(Mesh& mesh, const Vec3d& t, const double q[4]);

} // namespace lodbake
