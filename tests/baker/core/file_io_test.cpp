#include "lodbake/core/file_io.h"

#include <filesystem>

#include <gtest/gtest.h>

#include "test_paths.h"

using namespace lodbake;
namespace fs = std::filesystem;

namespace {
std::string freshDir(const std::string& name) {
    const std::string d = lodbake_test::scratchDir() + "/" + name;
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}
} // namespace

TEST(FileIoTest, ReadMissingFileNamesPath) {
    const auto r = readFileBytes("/nonexistent/dir/x.ply");
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.status().code(), StatusCode::IoError);
    EXPECT_NE(r.status().message().find("/nonexistent/dir/x.ply"), std::string::npos);
}

TEST(FileIoTest, ReadRefusesDirectoryAndOversize) {
    const std::string d = freshDir("read_limits");
    EXPECT_FALSE(readFileBytes(d).ok());
    ASSERT_TRUE(writeFileAtomic(d + "/f", "0123456789", 10).ok());
    const auto r = readFileBytes(d + "/f", 5);
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.status().code(), StatusCode::ResourceLimit);
    EXPECT_EQ(readFileBytes(d + "/f")->size(), 10u);
}

TEST(FileIoTest, UncommittedWriterLeavesNothing) {
    const std::string d = freshDir("atomic_discard");
    {
        AtomicFileWriter w;
        ASSERT_TRUE(w.add(d + "/a.bin", std::string("abc")).ok());
        ASSERT_TRUE(w.add(d + "/b.bin", std::string("def")).ok());
    }
    EXPECT_TRUE(fs::is_empty(d));
}

TEST(FileIoTest, CommitPublishesAllFiles) {
    const std::string d = freshDir("atomic_commit");
    AtomicFileWriter w;
    ASSERT_TRUE(w.add(d + "/a.bin", std::string("abc")).ok());
    ASSERT_TRUE(w.add(d + "/b.bin", std::string("")).ok());
    ASSERT_TRUE(w.commit().ok());
    EXPECT_EQ(readFileBytes(d + "/a.bin")->size(), 3u);
    EXPECT_TRUE(fs::exists(d + "/b.bin"));
    size_t count = 0;
    for (const auto& e : fs::directory_iterator(d)) count += e.is_regular_file();
    EXPECT_EQ(count, 2u);
}

TEST(FileIoTest, WriteIntoMissingFolderFailsCleanly) {
    const Status s = writeFileAtomic("/nonexistent/dir/out.glb", "x", 1);
    EXPECT_FALSE(s.ok());
    EXPECT_NE(s.message().find("/nonexistent/dir/out.glb"), std::string::npos);
}

TEST(FileIoTest, PathHelpers) {
    EXPECT_EQ(lowerExtension("a/b/Mesh.PLY"), ".ply");
    EXPECT_EQ(lowerExtension("noext"), "");
    EXPECT_EQ(parentDirectory("a/b/c.obj"), "a/b");
    EXPECT_EQ(joinPath("", "x.mtl"), "x.mtl");
    EXPECT_EQ(joinPath("a", "x.mtl"), "a/x.mtl");
}
