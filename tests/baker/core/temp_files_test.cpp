// The temporary-file registry: a process killed by SIGTERM/SIGINT while an AtomicFileWriter holds a
// staged temporary removes it before dying by that signal.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>
#include <string>

#include "lodbake/core/file_io.h"
#include "lodbake/core/temp_files.h"
#include "test_paths.h"

namespace {

namespace fs = std::filesystem;

std::string freshDir(const std::string& name) {
    const std::string dir = lodbake_test::scratchDir() + "/" + name + "_" + std::to_string(::getpid());
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

size_t entryCount(const std::string& dir) {
    size_t n = 0;
    for (const auto& e : fs::directory_iterator(dir)) {
        (void)e;
        ++n;
    }
    return n;
}

// Forks a child that stages a file (and keeps it uncommitted) and then receives `sig`.
int stageThenSignal(const std::string& dir, int sig, bool install_cleanup) {
    const pid_t pid = ::fork();
    if (pid == 0) {
        if (install_cleanup) lodbake::installTempFileSignalCleanup();
        lodbake::AtomicFileWriter writer;
        const std::string data(100000, 'x');
        if (!writer.add(dir + "/pack.glb", data).ok()) ::_exit(3);
        if (!writer.add(dir + "/report.json", data).ok()) ::_exit(3);
        ::raise(sig);
        ::_exit(4); // not reached when the signal kills the process
    }
    int status = 0;
    ::waitpid(pid, &status, 0);
    return status;
}

TEST(TempFilesTest, SignalRemovesStagedTemporariesAndKillsTheProcess) {
    for (int sig : {SIGTERM, SIGINT}) {
        const std::string dir = freshDir("temp_files_signal");
        const int status = stageThenSignal(dir, sig, true);
        ASSERT_TRUE(WIFSIGNALED(status)) << "exit status " << status;
        EXPECT_EQ(WTERMSIG(status), sig);
        EXPECT_EQ(entryCount(dir), 0u) << "temporaries left in " << dir;
    }
}

TEST(TempFilesTest, WithoutTheHandlerTheTemporariesStay) {
    // The control for the test above: the default action leaves the staged files behind.
    const std::string dir = freshDir("temp_files_control");
    const int status = stageThenSignal(dir, SIGTERM, false);
    ASSERT_TRUE(WIFSIGNALED(status));
    EXPECT_EQ(entryCount(dir), 2u);
}

TEST(TempFilesTest, SlotsAreReusedAfterUnregistering) {
    std::vector<int> slots;
    for (int i = 0; i < lodbake::kMaxTempFiles; ++i)
        slots.push_back(lodbake::registerTempFile("/nonexistent/" + std::to_string(i)));
    EXPECT_EQ(lodbake::registerTempFile("/nonexistent/full"), -1);
    for (int s : slots) EXPECT_GE(s, 0);
    for (int s : slots) lodbake::unregisterTempFile(s);
    const int again = lodbake::registerTempFile("/nonexistent/again");
    EXPECT_GE(again, 0);
    lodbake::unregisterTempFile(again);
    EXPECT_EQ(lodbake::registerTempFile(std::string(5000, 'a')), -1); // too long for a slot
}

TEST(TempFilesTest, ConcurrentWritersOfOneProcessUseDistinctTemporaries) {
    const std::string dir = freshDir("temp_files_two_writers");
    lodbake::AtomicFileWriter a, b;
    ASSERT_TRUE(a.add(dir + "/same.bin", std::string("first")).ok());
    ASSERT_TRUE(b.add(dir + "/same.bin", std::string("second")).ok());
    EXPECT_EQ(entryCount(dir), 2u);
    ASSERT_TRUE(a.commit().ok());
    ASSERT_TRUE(b.commit().ok());
    EXPECT_EQ(entryCount(dir), 1u);
}

} // namespace
