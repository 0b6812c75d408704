#pragma once
// A PFRep model's meshes as vectors, for tests that compare levels and refined meshes.

#include <cstddef>
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>

#include "lodrt/pfrep.h"

namespace lodbake_test {

/// Level k's triangles (3 ids each). With `result`, the extraction's result is stored there (and the
/// list is empty unless Ok); without it, anything but Ok fails the test.
inline std::vector<uint32_t> pfrepLevel(const lodrt::PfrepModel& m, uint32_t k, lodrt::Result* result = nullptr) {
    std::vector<uint32_t> idx(size_t(m.level0_triangles) * 3 + 3);
    size_t n = 0;
    const lodrt::Result r = lodrt::pfrepExtractLevel(m, k, idx.data(), idx.size() / 3, &n);
    if (result)
        *result = r;
    else
        EXPECT_EQ(r, lodrt::Result::Ok);
    idx.resize(r == lodrt::Result::Ok ? n * 3 : 0);
    return idx;
}

/// Level k as fan records (pfrepExtractLevelFans).
inline std::vector<uint32_t> pfrepLevelFans(const lodrt::PfrepModel& m, uint32_t k) {
    std::vector<uint32_t> values(lodrt::pfrepMaxFanValues(m) + 4);
    size_t n = 0;
    EXPECT_EQ(lodrt::pfrepExtractLevelFans(m, k, values.data(), values.size(), &n), lodrt::Result::Ok);
    values.resize(n);
    return values;
}

/// The mesh an instance mask selects (pfrepExtractSelective).
inline std::vector<uint32_t> pfrepSelective(const lodrt::PfrepModel& m, const std::vector<uint8_t>& mask) {
    std::vector<uint32_t> idx(size_t(m.level0_triangles) * 3 + 3);
    size_t n = 0;
    EXPECT_EQ(lodrt::pfrepExtractSelective(m, mask.data(), idx.data(), idx.size() / 3, &n), lodrt::Result::Ok);
    idx.resize(n * 3);
    return idx;
}

} // namespace lodbake_test
