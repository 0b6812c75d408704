#include <cstring>

#include <gtest/gtest.h>

#include "lodrt/lodrt.h"

TEST(VersionTest, MatchesProjectVersion) { EXPECT_STREQ(lodrt::versionString(), LODRT_TEST_EXPECTED_VERSION); }
