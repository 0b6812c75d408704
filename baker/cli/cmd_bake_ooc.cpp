// The out-of-core route of `lodbake bake` (cmd_bake_ooc.h).
#include "cmd_bake_ooc.h"

#include <cmath>

#include "lodbake/core/file_io.h"
#include "lodbake/core/math.h"
#include "lodbake/ooc/ooc_pack.h"

namespace lodbake::cli {

ooc::OocPackOptions outOfCorePackOptions(const BakeSettings& s, const std::string& input, const std::string& output,
                                         const std::string& work_dir, const ReadOptions& read, uint64_t limit,
                                         uint32_t threads) {
    ooc::OocPackOptions o;
    std::string dir = work_dir.empty() ? parentDirectory(output) : work_dir;
    o.driver.work_dir = dir.empty() ? "." : dir;
    o.driver.memory_limit_bytes = limit;
    o.driver.threads = int(threads);
    o.driver.read.max_polygon_vertices = read.max_polygon_vertices;
    o.driver.leaf_triangles = ooc::leafTrianglesForLimit(limit, o.driver.read, o.driver.sample_cap);
    o.driver.merge_group_bytes = ooc::kPartitionBuildBytesPerTriangle * o.driver.leaf_triangles;
    o.name = inputGroupName(input);
    o.lod_ratios = s.lod_ratios;
    o.screen.pixel_threshold = s.pixel_threshold;
    o.screen.viewport_height_px = s.viewport_height_px;
    o.screen.vertical_fov_rad = s.vertical_fov_deg * kPi / 180.0;
    o.hysteresis = s.hysteresis;
    o.valence.position_bits = s.stream_precision.position_bits;
    o.valence.normal_bits = s.stream_precision.normal_bits;
    o.valence.adaptive = s.stream_precision.adaptive;
    o.valence.error_fraction = s.stream_precision.error_fraction;
    o.compact = s.compact;
    o.distance.sample_count = s.error_samples;
    o.remove_covered_components = s.remove_covered_components;
    o.driver.pages.pack.position_bits = o.valence.position_bits;
    return o;
}

OutOfCoreBake outOfCoreBaker(const std::string& work_dir, const ReadOptions& read) {
    return [work_dir, read](const BakeJob& job, const std::string& glb_path, uint64_t limit, uint32_t threads,
                            Diagnostics& diagnostics) -> Result<OutOfCorePack> {
        const ooc::OocPackOptions o =
            outOfCorePackOptions(job.settings, job.inputs[0], job.output, work_dir, read, limit, threads);
        LODBAKE_ASSIGN_OR_RETURN(ooc::OocPackResult made,
                                 ooc::writeOutOfCorePack(job.inputs[0], glb_path, o, diagnostics));
        OutOfCorePack pack;
        pack.pack_bytes = made.pack_bytes;
        pack.report.name = o.name;
        pack.report.input_triangles = made.input_triangles;
        pack.report.input_vertices = made.input_vertices;
        pack.report.metrics = made.metrics;
        const ooc::OutOfCoreResult& d = made.driver;
        pack.stage_seconds = {{BakeStage::LodChain, d.partition.seconds + d.build.seconds + d.merge.seconds},
                              {BakeStage::Measure, made.measure_seconds},
                              {BakeStage::Encode, d.pages.seconds + made.cut_seconds},
                              {BakeStage::Pack, made.pack_seconds}};
        return pack;
    };
}

} // namespace lodbake::cli
