#pragma once
// Every mesh of ../shared/meshes the bake can take as one input (paths relative to that folder),
// for the determinism test and the batch benchmark.
#include <string>
#include <vector>

namespace lodbake_test {

inline std::vector<std::string> allSharedMeshNames() {
    return {"bunny_scan_bun000.ply",
            "bunny_scan_bun000_tri.ply",
            "bunny_zipper.ply",
            "dragon_poisson.ply",
            "dragon_scan_stand0_tri.ply",
            "dragon_stand_merged.ply",
            "fandisk.obj",
            "igea.ply",
            "igea_tristrips.ply",
            "lee_perry_smith/LeePerrySmith.glb",
            "lucy100k.ply",
            "nefertiti.obj",
            "nefertiti_fraunhofer_textured.glb",
            "range_scans/dragon_stand/dragonStandRight.conf",
            "rocker_arm.obj",
            "spot.obj"};
}

} // namespace lodbake_test
