// Depfiles: Makefile escaping that Ninja and GNU Make read back, one rule per target.
#include <gtest/gtest.h>

#include "lodbake/bake/depfile.h"

namespace {

using lodbake::escapeMakePath;
using lodbake::formatDepfile;

TEST(DepfileTest, EscapesSpacesHashesAndDollars) {
    EXPECT_EQ(escapeMakePath("assets/rock.obj"), "assets/rock.obj");
    EXPECT_EQ(escapeMakePath("my assets/rock 1.obj"), "my\\ assets/rock\\ 1.obj");
    EXPECT_EQ(escapeMakePath("a#b"), "a\\#b");
    EXPECT_EQ(escapeMakePath("price$1"), "price$$1");
    // A backslash run before an escaped space doubles; elsewhere backslashes stay.
    EXPECT_EQ(escapeMakePath("a\\ b"), "a\\\\\\ b");
    EXPECT_EQ(escapeMakePath("c:\\x\\y"), "c:\\x\\y");
}

TEST(DepfileTest, OneRulePerTargetWithDuplicatesDropped) {
    const std::string text = formatDepfile(
        {{"out/a.glb", {"a.obj", "a.mtl", "tex a.png", "a.obj", "p.json"}}, {"out/b.glb", {"b.ply", "p.json"}}});
    EXPECT_EQ(text, "out/a.glb: \\\n  a.obj \\\n  a.mtl \\\n  tex\\ a.png \\\n  p.json\n"
                    "out/b.glb: \\\n  b.ply \\\n  p.json\n");
}

} // namespace
