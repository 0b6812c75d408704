// libFuzzer target for the out-of-core job list's files (lodbake/ooc/jobs.h): every input parsed as
// a plan and as a job record; a failure must be one line starting with the file's path, a success
// must print and read back unchanged. Run with scripts/fuzz.sh jobs SECONDS.
#include <cstddef>
#include <cstdint>
#include <string>

#include "lodbake/ooc/jobs.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    const std::string plan_path = "work/plan.json", record_path = "work/job-x.json";
    const lodbake::Result<lodbake::ooc::JobPlan> plan = lodbake::ooc::parseJobPlan(text, plan_path);
    if (!plan.ok()) {
        const std::string& m = plan.status().message();
        if (m.rfind(plan_path, 0) != 0 || m.find('\n') != std::string::npos) __builtin_trap();
    } else {
        const std::string printed = lodbake::ooc::jobPlanJson(*plan);
        const auto again = lodbake::ooc::parseJobPlan(printed, plan_path);
        if (!again.ok() || lodbake::ooc::jobPlanJson(*again) != printed) __builtin_trap();
        for (size_t i = 0; i < plan->jobs.size(); ++i)
            if (again->jobs[i].hash != plan->jobs[i].hash) __builtin_trap();
    }
    const lodbake::Result<lodbake::ooc::JobRecord> record = lodbake::ooc::parseJobRecord(text, record_path);
    if (!record.ok()) {
        const std::string& m = record.status().message();
        if (m.rfind(record_path, 0) != 0 || m.find('\n') != std::string::npos) __builtin_trap();
    } else {
        const std::string printed = lodbake::ooc::jobRecordJson(*record);
        const auto again = lodbake::ooc::parseJobRecord(printed, record_path);
        if (!again.ok() || lodbake::ooc::jobRecordJson(*again) != printed) __builtin_trap();
    }
    return 0;
}
