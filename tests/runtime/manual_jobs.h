#pragma once
// Test helpers: a lodrt::JobSystem whose queue the test drains by hand, to show the streamer's
// update() never waits for a job; and one that runs every job on its own thread.

#include <deque>
#include <thread>
#include <utility>
#include <vector>

#include "lodrt/streaming.h"

namespace lodrt_test {

struct ManualJobs {
    std::deque<std::pair<void (*)(void*), void*>> queue;
    static void submit(void* user, void (*run)(void*), void* task) {
        static_cast<ManualJobs*>(user)->queue.push_back({run, task});
    }
    void runAll() {
        while (!queue.empty()) {
            auto job = queue.front();
            queue.pop_front();
            job.first(job.second);
        }
    }
    lodrt::JobSystem system() { return lodrt::JobSystem{&ManualJobs::submit, this}; }
};

// Each job on its own thread. The threads are joined however the test leaves the scope, so a failed
// assertion reports instead of terminating on a joinable std::thread.
struct ThreadJobs {
    std::vector<std::thread> running;
    static void submit(void* user, void (*run)(void*), void* task) {
        static_cast<ThreadJobs*>(user)->running.emplace_back(run, task);
    }
    ~ThreadJobs() {
        for (std::thread& t : running) t.join();
    }
    lodrt::JobSystem system() { return lodrt::JobSystem{&ThreadJobs::submit, this}; }
};

} // namespace lodrt_test
