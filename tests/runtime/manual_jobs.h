#pragma once
// Test helper: a lodrt::JobSystem whose queue the test drains by hand, to show the streamer's
// update() never waits for a job.

#include <deque>
#include <utility>

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

} // namespace lodrt_test
