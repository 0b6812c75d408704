#include "core/parallel.h"

#include <atomic>
#include <chrono>
#include <cstdint>
#include <new>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

namespace {

using lodbake::BackgroundTasks;
using lodbake::ScopedThreadLimit;
using lodbake::Status;
using lodbake::StatusCode;

TEST(ParallelTest, BackgroundTasksHaveAllRunWhenWaitReturns) {
    for (size_t threads : {size_t(1), size_t(2)}) {
        ScopedThreadLimit limit(threads);
        std::vector<std::vector<uint32_t>> arrays(4);
        BackgroundTasks tasks;
        for (size_t t = 0; t < arrays.size(); ++t)
            tasks.run([&arrays, t] { arrays[t].assign(100000, uint32_t(t + 1)); });
        // The caller goes on with its own work meanwhile.
        uint64_t sum = 0;
        for (uint32_t i = 0; i < 1000000; ++i) sum += i;
        EXPECT_EQ(sum, 499999500000ull);
        const Status status = tasks.wait();
        EXPECT_TRUE(status.ok()) << status.message();
        for (size_t t = 0; t < arrays.size(); ++t) {
            ASSERT_EQ(arrays[t].size(), 100000u) << threads << " thread(s), task " << t;
            EXPECT_EQ(arrays[t].front(), uint32_t(t + 1));
            EXPECT_EQ(arrays[t].back(), uint32_t(t + 1));
        }
        // Waiting again (nothing left) is fine.
        EXPECT_TRUE(tasks.wait().ok());
    }
}

TEST(ParallelTest, BackgroundTasksReportOutOfMemory) {
    for (size_t threads : {size_t(1), size_t(2)}) {
        ScopedThreadLimit limit(threads);
        BackgroundTasks tasks;
        tasks.run([] { throw std::bad_alloc(); });
        const Status status = tasks.wait();
        EXPECT_EQ(status.code(), StatusCode::ResourceLimit) << threads << " thread(s)";
    }
}

TEST(ParallelTest, BackgroundTasksDestructorWaits) {
    for (size_t threads : {size_t(1), size_t(2)}) {
        ScopedThreadLimit limit(threads);
        std::atomic<bool> done{false};
        {
            BackgroundTasks tasks;
            tasks.run([&done] {
                std::this_thread::sleep_for(std::chrono::milliseconds(50));
                done = true;
            });
        } // an early return of the caller: the task must not outlive what it refers to
        EXPECT_TRUE(done.load()) << threads << " thread(s)";
    }
}

} // namespace
