#pragma once
// lodbake_scansim: a turntable range-scanner simulator that makes the project's own sample scans.
//
// A procedural object (a superquadric "rock" whose radius is displaced by seeded multi-octave value
// noise, standing on a cylindrical base) is scanned from `view_count` turntable positions. Per view
// a pinhole camera casts a regular grid of rays (num_cols x num_rows); the first hit of each ray is
// kept unless the point is shadowed from the projector (triangulation scanners need both to see it),
// seen at a grazing angle beyond the limit, or lost to a random speckle dropout. Kept points get
// Gaussian range noise along the viewing ray. Output is what a Stanford/Cyberware scan looks like:
// one PLY per view with `element range_grid`, in scanner coordinates, plus a .conf whose
// `bmesh name tx ty tz qx qy qz qw` lines bring each view into world coordinates as
// p_world = R(q)^T * p + t.
//
// Every random choice comes from a counter-based hash of (seed, view, cell, purpose), so the output
// is a pure function of the options, and changing one setting (say the noise sigma) leaves every
// other random choice (which cells are speckled) as it was.

#include <cstdint>
#include <string>
#include <vector>

#include "lodbake/core/status.h"

namespace lodbake::scansim {

struct Vec3d {
    double x = 0.0, y = 0.0, z = 0.0;
};

/// The scanned object. World frame: the turntable axis is +y, the base stands on y = 0. Metres.
struct ShapeOptions {
    double radius_x = 0.045; // superquadric semi-axes of the rock before displacement
    double radius_y = 0.034;
    double radius_z = 0.038;
    double exponent = 2.6;         // superquadric exponent: 2 is an ellipsoid, larger is boxier
    double noise_amplitude = 0.16; // radial displacement, as a fraction of the undisplaced radius
    double noise_frequency = 2.2;  // lowest octave's frequency over the unit sphere of directions
    int noise_octaves = 5;         // each octave doubles the frequency and halves the amplitude
    double rock_center_y = 0.048;  // height of the rock's centre above the turntable
    double base_radius = 0.036;    // cylindrical base (plinth) under the rock
    double base_height = 0.02;
};

struct ScanOptions {
    uint64_t seed = 1;         // drives the shape's noise and every scanner random choice
    std::string name = "rock"; // file names: <name>_<degrees>.ply and <name>.conf
    int view_count = 6;        // turntable positions, 360/view_count degrees apart
    uint32_t num_cols = 160;   // rays per view, horizontally
    uint32_t num_rows = 120;   // rays per view, vertically (row 0 is the bottom)
    // The pinhole camera sits at (0, 0, camera_distance) in scanner coordinates and looks down -z;
    // ray (col, row) aims at ((col + 0.5 - num_cols / 2) * pitch, (row + 0.5 - num_rows / 2) * pitch, 0)
    // with pitch = frame_height / num_rows. The projector sits at (projector_baseline, 0, camera_distance).
    double camera_distance = 0.45;     // camera to turntable axis, metres
    double frame_height = 0.125;       // height the grid covers at the turntable axis, metres (square pixels)
    double projector_baseline = 0.15;  // projector offset from the camera along scanner x, metres
    double range_noise_sigma = 0.0002; // Gaussian noise along the viewing ray, metres (0: none)
    double grazing_limit_deg = 75.0;   // drop points whose normal is further than this from the view ray
    double speckle_probability = 0.01; // chance that an otherwise good sample is lost
    bool simulate_shadows = true;      // drop points the projector cannot see
    bool write_confidence = false;     // add `property float confidence` (cosine of the view angle)
    bool binary = true;                // binary_little_endian (true) or ascii PLY
    ShapeOptions shape;
};

/// The object as an implicit function: negative inside, positive outside, zero on the surface.
class Shape {
public:
    Shape(const ShapeOptions& options, uint64_t seed);
    /// A value with the sign of the signed distance; |value| / lipschitz() does not exceed the distance.
    double field(const Vec3d& p) const;
    /// Outward unit normal (central differences of field()).
    Vec3d normal(const Vec3d& p) const;
    /// Bound of |grad field| (twice the largest slope measured around the surface, see the
    /// constructor): field(p) / lipschitz() is the sphere-tracing step.
    double lipschitz() const { return lipschitz_; }
    /// A sphere around the world origin that contains the whole object.
    double boundingRadius() const { return bounding_radius_; }

private:
    ShapeOptions options_;
    uint64_t seed_;
    double lipschitz_ = 1.0;
    double bounding_radius_ = 1.0;
    double rockField(const Vec3d& p) const;
};

/// Counts for one view. Every grid cell is exactly one of: miss, shadowed, grazing, speckle, kept.
struct ViewStats {
    uint64_t cells = 0;
    uint64_t hits = 0;            // rays that hit the object
    uint64_t dropped_shadow = 0;  // hit, but the projector cannot see the point
    uint64_t dropped_grazing = 0; // hit and lit, but seen beyond the grazing limit
    uint64_t dropped_speckle = 0; // would have been kept, lost to a random dropout
    uint64_t kept = 0;            // samples written
};

struct ScanView {
    std::string file_name;               // "<name>_<degrees>.ply"
    double turntable_deg = 0.0;          // rotation of the turntable for this view
    std::vector<int32_t> cell_vertex;    // num_rows * num_cols, row-major from the bottom row; -1: no sample
    std::vector<float> points;           // 3 per kept sample, scanner frame, in cell order
    std::vector<float> confidence;       // 1 per kept sample: cosine of the angle between normal and view ray
    double quaternion[4] = {0, 0, 0, 1}; // qx qy qz qw of the .conf line
    double translation[3] = {0, 0, 0};   // tx ty tz of the .conf line
    ViewStats stats;
};

struct ScanSet {
    std::vector<ScanView> views;
};

/// Checks the options (positive sizes, probabilities in [0,1], ...): an error names the bad field.
Status validateOptions(const ScanOptions& options);

/// Scans the object from every view. Deterministic for the given options.
Result<ScanSet> simulateScans(const ScanOptions& options);

/// The PLY file of one view (header with obj_info num_cols/num_rows, vertices, range_grid).
std::vector<uint8_t> rangeGridPlyBytes(const ScanView& view, const ScanOptions& options);

/// The .conf text: one `bmesh` line per view.
std::string confText(const ScanSet& scans);

/// Name of the .conf file: "<name>.conf".
std::string confFileName(const ScanOptions& options);

/// Writes every view and the .conf into `directory` (created if missing), atomically as a set.
Status writeScanSet(const ScanSet& scans, const ScanOptions& options, const std::string& directory);

/// Named option sets for the bundled samples ("rock"); an error for an unknown name.
Result<ScanOptions> presetOptions(const std::string& name);

/// The atlased reconstruction (atlas.cpp): the rock (without its plinth) as a closed cube-sphere
/// mesh of 6 × charts_per_edge² × quads_per_chart² quads, each cube face cut into
/// charts_per_edge² square charts. Every chart has its own UVs in its own cell of a square atlas
/// grid, so chart borders are UV seams (positions shared bit for bit, UVs not): the layout of an
/// automatic photogrammetry atlas, for simplification across seams.
struct AtlasOptions {
    uint32_t charts_per_edge = 6; // 216 charts
    uint32_t quads_per_chart = 5; // 10,800 triangles with the default charts
};

/// The atlased mesh as Wavefront OBJ text (v, vt, f v/vt). Deterministic for the given options.
Result<std::string> atlasObjText(const ScanOptions& options, const AtlasOptions& atlas);

/// Seeded lattice value noise in [-1, 1], C2-smooth; each octave number is an independent lattice.
double valueNoise(uint64_t seed, uint64_t octave, const Vec3d& p);

/// Uniform in (0, 1), never 0 or 1, from a counter-based hash of four words.
double hashUniform(uint64_t a, uint64_t b, uint64_t c, uint64_t d);

/// A procedural scan of any size (surface.cpp), written straight to a PLY while it is generated: a
/// torus (closed, genus 1, so every triangle has three neighbours and no pole needs special cases)
/// sampled on a rows x cols grid, displaced along its normal by seeded fractal value noise (the
/// scanned object's relief) and per-vertex Gaussian noise (the scanner's range noise). Memory is
/// one grid row whatever the size; the output is a pure function of the options.
struct SurfaceOptions {
    uint64_t seed = 1;
    uint64_t triangles = 1000000; // target; the grid makes 2 * rows * cols, the nearest it can
    enum class Encoding { BinaryLittleEndian, BinaryBigEndian, Ascii } encoding = Encoding::BinaryLittleEndian;
    double major_radius = 1.0;      // metres, centre of the tube to the torus axis (+y)
    double minor_radius = 0.4;      // metres, radius of the tube
    double relief = 0.08;           // fractal displacement amplitude, as a fraction of minor_radius
    double relief_frequency = 3.0;  // lowest octave's frequency in cycles per metre
    int relief_octaves = 6;         // each octave doubles the frequency and halves the amplitude
    double range_noise = 0.15;      // Gaussian noise sigma along the normal, in grid spacings
};

struct SurfaceStats {
    uint64_t rows = 0, cols = 0;
    uint64_t vertices = 0;
    uint64_t triangles = 0;
    uint64_t bytes = 0; // size of the file written
};

/// Grid size for the options: rows around the tube, cols around the axis (cols / rows follows the
/// ratio of the two circumferences, so grid cells are about square). An error for a target below
/// 18 triangles or above 2^36, or for vertex ids that would not fit 32 bits.
Result<SurfaceStats> surfaceGrid(const SurfaceOptions& options);

/// Writes the surface as PLY (`element vertex` with float x y z, then `element face` with
/// `list uchar int vertex_indices`, triangles facing outwards) to `path` through a temporary in the
/// same folder, renamed into place at the end: an error (a full disk names the path) or an
/// interruption leaves no file behind.
Result<SurfaceStats> writeSurfacePly(const SurfaceOptions& options, const std::string& path);

/// p_world = R(q)^T * p + t, the Stanford .conf convention.
Vec3d scannerToWorld(const Vec3d& p, const double quaternion[4], const double translation[3]);

} // namespace lodbake::scansim
