#pragma once
// The one place the baker touches TBB (STYLE.md §2): a fixed-grain parallel loop and a scoped thread
// limit. Callers parallelise over independent items and write into per-item slots, so the output
// never depends on the thread count or the schedule (STYLE.md §7).

#include <atomic>
#include <cstddef>
#include <exception>
#include <new>
#include <string>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/partitioner.h>
#include <tbb/task_group.h>

#include "lodbake/core/status.h"

namespace lodbake {

/// Number of chunks of `chunk_size` items covering `count` items.
inline size_t chunkCount(size_t count, size_t chunk_size) {
    return (count + chunk_size - 1) / chunk_size;
}

/// Calls fn(i) for every i in [0, count), `grain` consecutive items per task. fn must only write
/// state owned by item i. TBB task exceptions (bad_alloc) are caught here and become a Status;
/// fn itself must not throw.
template <class Fn> Status parallelFor(size_t count, size_t grain, Fn&& fn) {
    if (count == 0) return Status::okStatus();
    try {
        tbb::parallel_for(
            tbb::blocked_range<size_t>(0, count, grain > 0 ? grain : 1),
            [&fn](const tbb::blocked_range<size_t>& range) {
                for (size_t i = range.begin(); i != range.end(); ++i) fn(i);
            },
            tbb::simple_partitioner());
    } catch (const std::bad_alloc&) {
        return resourceLimit("out of memory in a parallel task");
    } catch (const std::exception& e) {
        return internalError(std::string("parallel task failed: ") + e.what());
    }
    return Status::okStatus();
}

/// Calls fn(chunk, first, last) for the consecutive ranges [first, last) of `chunk_size` items
/// (the last one shorter) that cover [0, count), one task per range. The ranges depend on count and
/// chunk_size alone, so per-chunk results (counts, buffers, cursors) are the same at any thread count.
template <class Fn> Status parallelForChunks(size_t count, size_t chunk_size, Fn&& fn) {
    const size_t size = chunk_size > 0 ? chunk_size : 1;
    return parallelFor(chunkCount(count, size), 1, [&](size_t chunk) {
        const size_t first = chunk * size;
        fn(chunk, first, first + size < count ? first + size : count);
    });
}

/// Runs items 0 .. count-1 through three stages, at most `slots` items at once: read(i, slot) one
/// item at a time in increasing i, work(i, slot) on any number of items in parallel, write(i, slot)
/// one item at a time in increasing i. Item i uses slot i % slots, which no other item uses until
/// item i is written (an item enters only when fewer than `slots` are alive, and items leave in
/// order), so a stage may keep its item's data in the caller's slot. Unlike batches of parallelFor,
/// the next items are read and the finished ones written while others are worked on, and no thread
/// waits for the slowest item of a batch. Each stage returns a Status: after a failure no further
/// item is read, and the result is the failure of the lowest item (an item whose read failed is not
/// worked on; items after a failed one are not written). fn must not throw; bad_alloc is caught
/// and becomes a Status.
template <class Read, class Work, class Write>
Status orderedPipeline(size_t count, size_t slots, Read&& read, Work&& work, Write&& write) {
    if (count == 0) return Status::okStatus();
    slots = slots > 0 ? slots : 1;
    struct Item {
        size_t index = 0;
        Status status = Status::okStatus();
    };
    std::atomic<bool> failed{false};
    size_t next = 0;
    Status result = Status::okStatus();
    try {
        const auto read_stage = [&](tbb::flow_control& fc) {
            Item item;
            if (next == count || failed.load()) {
                fc.stop();
                return item;
            }
            item.index = next++;
            item.status = read(item.index, item.index % slots);
            if (!item.status.ok()) failed.store(true);
            return item;
        };
        const auto work_stage = [&](Item item) {
            if (item.status.ok()) item.status = work(item.index, item.index % slots);
            if (!item.status.ok()) failed.store(true);
            return item;
        };
        const auto write_stage = [&](const Item& item) {
            if (!result.ok()) return;
            result = item.status.ok() ? write(item.index, item.index % slots) : item.status;
            if (!result.ok()) failed.store(true);
        };
        tbb::parallel_pipeline(slots, tbb::make_filter<void, Item>(tbb::filter_mode::serial_in_order, read_stage) &
                                          tbb::make_filter<Item, Item>(tbb::filter_mode::parallel, work_stage) &
                                          tbb::make_filter<Item, void>(tbb::filter_mode::serial_in_order, write_stage));
    } catch (const std::bad_alloc&) {
        return resourceLimit("out of memory in a parallel task");
    } catch (const std::exception& e) {
        return internalError(std::string("parallel task failed: ") + e.what());
    }
    return result;
}

/// Runs work that an idle worker thread may pick up while the caller goes on: each fn given to run()
/// is a task, and wait() returns once every one has run (running those no worker took on the calling
/// thread, so with one thread they run in wait()). For work whose result does not depend on when or
/// on which thread it runs, on state the caller leaves alone until wait() (e.g. allocating and
/// filling an array). fn must not throw; bad_alloc is caught and becomes a Status. The destructor
/// waits, so an early return cannot leave a task running.
class BackgroundTasks {
public:
    BackgroundTasks() = default;
    BackgroundTasks(const BackgroundTasks&) = delete;
    BackgroundTasks& operator=(const BackgroundTasks&) = delete;
    ~BackgroundTasks() { (void)wait(); }

    template <class Fn> void run(Fn&& fn) { group_.run(std::forward<Fn>(fn)); }

    Status wait() {
        try {
            group_.wait();
        } catch (const std::bad_alloc&) {
            return resourceLimit("out of memory in a background task");
        } catch (const std::exception& e) {
            return internalError(std::string("background task failed: ") + e.what());
        }
        return Status::okStatus();
    }

private:
    tbb::task_group group_;
};

/// How many threads parallel loops may use now (ScopedThreadLimit's limit, else the machine's).
inline size_t maxParallelism() {
    return tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism);
}

/// Limits the worker threads TBB may use while it is alive (CLI --threads, determinism tests).
class ScopedThreadLimit {
public:
    explicit ScopedThreadLimit(size_t thread_count)
        : control_(tbb::global_control::max_allowed_parallelism, thread_count > 0 ? thread_count : 1) {}

private:
    tbb::global_control control_;
};

} // namespace lodbake
