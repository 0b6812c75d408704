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

// Items are written in order, a slot is never used by two items at once, and the failure reported is
// the lowest item's, whatever finished first.
TEST(ParallelTest, OrderedPipelineWritesInOrderAndKeepsSlotsApart) {
    for (size_t threads : {size_t(1), size_t(2)}) {
        for (size_t slots : {size_t(1), size_t(3), size_t(8)}) {
            ScopedThreadLimit limit(threads);
            const size_t count = 200;
            std::vector<std::atomic<int>> busy(slots);
            std::vector<uint64_t> value(slots, 0);
            std::vector<size_t> written;
            std::atomic<bool> overlap{false};
            const Status status = lodbake::orderedPipeline(
                count, slots,
                [&](size_t i, size_t s) {
                    if (busy[s].fetch_add(1) != 0) overlap = true;
                    value[s] = i;
                    return Status::okStatus();
                },
                [&](size_t i, size_t s) {
                    // Uneven work, so later items often finish first.
                    std::this_thread::sleep_for(std::chrono::microseconds((i * 7919) % 300));
                    value[s] = value[s] * 3 + 1;
                    return Status::okStatus();
                },
                [&](size_t i, size_t s) {
                    if (value[s] != 3 * uint64_t(i) + 1) overlap = true;
                    written.push_back(i);
                    busy[s].fetch_sub(1);
                    return Status::okStatus();
                });
            ASSERT_TRUE(status.ok()) << status.message();
            EXPECT_FALSE(overlap) << threads << " thread(s), " << slots << " slots";
            ASSERT_EQ(written.size(), count);
            for (size_t i = 0; i < count; ++i) EXPECT_EQ(written[i], i);
        }
    }
}

TEST(ParallelTest, OrderedPipelineReportsTheLowestFailure) {
    for (size_t threads : {size_t(1), size_t(2)}) {
        ScopedThreadLimit limit(threads);
        std::vector<size_t> written;
        size_t reads = 0;
        const Status status = lodbake::orderedPipeline(
            100, 4,
            [&](size_t i, size_t) {
                ++reads;
                return i == 40 ? lodbake::ioError("read 40") : Status::okStatus();
            },
            [&](size_t i, size_t) {
                if (i == 37) std::this_thread::sleep_for(std::chrono::milliseconds(5));
                return i == 37 ? lodbake::invalidInput("work 37") : Status::okStatus();
            },
            [&](size_t i, size_t) {
                written.push_back(i);
                return Status::okStatus();
            });
        EXPECT_EQ(status.message(), "work 37") << threads << " thread(s)";
        EXPECT_LE(reads, 41u); // nothing is read after the failed read
        ASSERT_EQ(written.size(), 37u);
        EXPECT_EQ(written.back(), 36u);
        const Status thrown = lodbake::orderedPipeline(
            10, 2, [](size_t, size_t) { return Status::okStatus(); },
            [](size_t i, size_t) -> Status {
                if (i == 5) throw std::bad_alloc();
                return Status::okStatus();
            },
            [](size_t, size_t) { return Status::okStatus(); });
        EXPECT_EQ(thrown.code(), StatusCode::ResourceLimit);
    }
}
