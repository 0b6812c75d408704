// The out-of-core job list (lodbake/ooc/jobs.h): every job of a plan run one by one, in plan order
// and in another order the dependencies allow, and through the CLI in separate processes, gives the
// bytes buildOutOfCore writes; a re-run writes the same bytes; missing inputs, a corrupted input
// file and a truncated, edited or hostile plan or record are refused naming the file, with no record
// left.

#include "lodbake/ooc/jobs.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "cli_runner.h"
#include "lodbake/core/file_io.h"
#include "ooc_scans.h"

namespace fs = std::filesystem;
using namespace lodbake::ooc;

namespace {

std::string jobsDir(const std::string& name) { return lodbake_test::freshOocDir("ooc_jobs", name); }

std::string jobsScan(const std::string& dir, uint64_t triangles) { return lodbake_test::writeGeneratedScan(dir, triangles); }

OutOfCoreOptions jobsOptions(const std::string& work, int threads) {
    return lodbake_test::smallDriverOptions(work, uint64_t(256) << 20, threads);
}

std::vector<uint8_t> fileBytes(const std::string& path) {
    auto b = lodbake::readFileBytes(path);
    return b.ok() ? *b : std::vector<uint8_t>();
}

struct DriverBytes {
    std::vector<uint8_t> pages, table;
    uint64_t partitions = 0, merges = 0;
};

DriverBytes driverBytes(const std::string& scan, const std::string& dir, const OutOfCoreOptions& o) {
    lodbake::Diagnostics d;
    auto r = buildOutOfCore(scan, dir + "/driver.bin", o, d);
    EXPECT_TRUE(r.ok()) << r.status().message();
    DriverBytes b;
    if (!r.ok()) return b;
    b.pages = fileBytes(dir + "/driver.bin");
    b.table = r->table;
    b.partitions = r->partition_count;
    b.merges = r->merge_count;
    return b;
}

// Plans and runs every ready job until the plan is complete and done; `reverse` runs each batch of
// ready jobs last first. Returns the number of --plan steps.
int runPlan(const std::string& scan, const std::string& work, const OutOfCoreOptions& o, bool reverse) {
    lodbake::Diagnostics d;
    for (int step = 1; step < 100; ++step) {
        auto plan = planOutOfCore(scan, work, o, d);
        EXPECT_TRUE(plan.ok()) << plan.status().message();
        if (!plan.ok()) return -1;
        JobProgress p = jobProgress(work, *plan);
        if (plan->complete && p.done.size() == p.total) return step;
        EXPECT_FALSE(p.ready.empty());
        if (reverse) std::reverse(p.ready.begin(), p.ready.end());
        for (const std::string& id : p.ready) {
            JobRunOptions ro;
            ro.memory_limit_bytes = o.memory_limit_bytes;
            auto r = runJob(work, id, ro, d);
            EXPECT_TRUE(r.ok()) << id << ": " << r.status().message();
            if (!r.ok()) return -1;
        }
    }
    return -1;
}

// Runs jobs until the plan lists merge jobs, and returns the first merge job.
std::string planUntilMerges(const std::string& scan, const std::string& work, const OutOfCoreOptions& o) {
    lodbake::Diagnostics d;
    for (int step = 0; step < 3; ++step) {
        auto plan = planOutOfCore(scan, work, o, d);
        EXPECT_TRUE(plan.ok()) << plan.status().message();
        if (!plan.ok()) return std::string();
        for (const JobSpec& j : plan->jobs)
            if (j.kind == JobKind::Merge) return j.id;
        for (const std::string& id : jobProgress(work, *plan).ready) EXPECT_TRUE(runJob(work, id, {}, d).ok());
    }
    return std::string();
}

bool mentions(const lodbake::Status& s, const std::string& what) {
    return s.message().find(what) != std::string::npos && s.message().find('\n') == std::string::npos;
}

TEST(OocJobsTest, EveryJobOneByOneGivesTheDriversBytesInAnyOrder) {
    const std::string dir = jobsDir("same");
    const std::string scan = jobsScan(dir, 60000);
    const DriverBytes driver = driverBytes(scan, dir, jobsOptions(dir + "/driver_work", 2));
    ASSERT_FALSE(driver.pages.empty());
    ASSERT_GT(driver.partitions, 2u);
    ASSERT_GT(driver.merges, 1u);
    for (const bool reverse : {false, true}) {
        const std::string work = dir + (reverse ? "/reverse" : "/forward");
        const int steps = runPlan(scan, work, jobsOptions(work, 1), reverse);
        EXPECT_GT(steps, 2);
        auto result = plannedResult(work);
        ASSERT_TRUE(result.ok()) << result.status().message();
        EXPECT_EQ(result->partition_count, driver.partitions);
        EXPECT_EQ(result->merge_count, driver.merges);
        EXPECT_EQ(fileBytes(result->output), driver.pages) << (reverse ? "reverse" : "forward");
        EXPECT_EQ(result->table, driver.table);
        // The plan is complete: planning again adds nothing.
        const std::string before = lodbake_test::readTextFile(jobPlanPath(work));
        lodbake::Diagnostics d;
        ASSERT_TRUE(planOutOfCore(scan, work, jobsOptions(work, 1), d).ok());
        EXPECT_EQ(lodbake_test::readTextFile(jobPlanPath(work)), before);
    }
}

TEST(OocJobsTest, ARerunWritesTheSameBytes) {
    const std::string dir = jobsDir("rerun");
    const std::string scan = jobsScan(dir, 30000);
    const std::string work = dir + "/work";
    ASSERT_GT(runPlan(scan, work, jobsOptions(work, 2), false), 0);
    auto plan = readJobPlan(jobPlanPath(work));
    ASSERT_TRUE(plan.ok());
    lodbake::Diagnostics d;
    for (const std::string& id : {plan->jobs.front().id, plan->jobs[plan->jobs.size() - 2].id, std::string("pages")}) {
        const std::string record_before = lodbake_test::readTextFile(jobRecordPath(work, id));
        auto before = readJobRecord(jobRecordPath(work, id));
        ASSERT_TRUE(before.ok());
        const std::vector<uint8_t> output_before = fileBytes(work + "/" + before->output);
        auto again = runJob(work, id, {}, d);
        ASSERT_TRUE(again.ok()) << again.status().message();
        EXPECT_EQ(lodbake_test::readTextFile(jobRecordPath(work, id)), record_before) << id;
        EXPECT_EQ(fileBytes(work + "/" + again->output), output_before) << id;
    }
}

TEST(OocJobsTest, MissingInputsAreRefusedNamingThem) {
    const std::string dir = jobsDir("missing");
    const std::string scan = jobsScan(dir, 60000);
    const std::string work = dir + "/work";
    const OutOfCoreOptions o = jobsOptions(work, 2);
    const std::string merge = planUntilMerges(scan, work, o);
    ASSERT_FALSE(merge.empty());
    auto plan = readJobPlan(jobPlanPath(work));
    ASSERT_TRUE(plan.ok());
    const JobSpec* spec = plan->find(merge);
    ASSERT_NE(spec, nullptr);
    const std::string dep = spec->inputs[0].job;
    lodbake::Diagnostics d;
    // The record of a job it depends on is missing.
    const std::string dep_record = jobRecordPath(work, dep);
    fs::rename(dep_record, dep_record + ".away");
    auto r = runJob(work, merge, {}, d);
    ASSERT_FALSE(r.ok());
    EXPECT_TRUE(mentions(r.status(), dep_record)) << r.status().message();
    EXPECT_FALSE(fs::exists(jobRecordPath(work, merge)));
    fs::rename(dep_record + ".away", dep_record);
    // That job's output is missing.
    auto rec = readJobRecord(dep_record);
    ASSERT_TRUE(rec.ok());
    const std::string dep_output = work + "/" + rec->output;
    fs::rename(dep_output, dep_output + ".away");
    r = runJob(work, merge, {}, d);
    ASSERT_FALSE(r.ok());
    EXPECT_TRUE(mentions(r.status(), dep_output)) << r.status().message();
    fs::rename(dep_output + ".away", dep_output);
    // A partition file is missing.
    const std::string part = work + "/" + plan->jobs[0].inputs[0].file;
    fs::rename(part, part + ".away");
    r = runJob(work, plan->jobs[0].id, {}, d);
    ASSERT_FALSE(r.ok());
    EXPECT_TRUE(mentions(r.status(), part)) << r.status().message();
    fs::rename(part + ".away", part);
    // An id the plan does not list.
    r = runJob(work, "merge-999", {}, d);
    ASSERT_FALSE(r.ok());
    EXPECT_TRUE(mentions(r.status(), jobPlanPath(work))) << r.status().message();
    // With everything back the job runs.
    EXPECT_TRUE(runJob(work, merge, {}, d).ok());
}

TEST(OocJobsTest, CorruptedInputsAreRefusedNamingTheFile) {
    const std::string dir = jobsDir("corrupt");
    const std::string scan = jobsScan(dir, 60000);
    const std::string work = dir + "/work";
    const OutOfCoreOptions o = jobsOptions(work, 2);
    const std::string merge = planUntilMerges(scan, work, o);
    ASSERT_FALSE(merge.empty());
    auto plan = readJobPlan(jobPlanPath(work));
    ASSERT_TRUE(plan.ok());
    auto rec = readJobRecord(jobRecordPath(work, plan->find(merge)->inputs[1].job));
    ASSERT_TRUE(rec.ok());
    const std::string input = work + "/" + rec->output;
    const std::vector<uint8_t> good = fileBytes(input);
    std::vector<uint8_t> bad = good;
    bad[bad.size() / 2] ^= 0x40;
    ASSERT_TRUE(lodbake::writeFileAtomic(input, bad.data(), bad.size()).ok());
    lodbake::Diagnostics d;
    auto r = runJob(work, merge, {}, d);
    ASSERT_FALSE(r.ok());
    EXPECT_TRUE(mentions(r.status(), input)) << r.status().message();
    EXPECT_TRUE(mentions(r.status(), "corrupted")) << r.status().message();
    EXPECT_FALSE(fs::exists(jobRecordPath(work, merge)));
    // A partition file changed after the plan named it.
    const std::string part = work + "/" + plan->jobs[0].inputs[0].file;
    std::vector<uint8_t> part_bytes = fileBytes(part);
    part_bytes[part_bytes.size() - 1] ^= 0x01;
    ASSERT_TRUE(lodbake::writeFileAtomic(part, part_bytes.data(), part_bytes.size()).ok());
    r = runJob(work, plan->jobs[0].id, {}, d);
    ASSERT_FALSE(r.ok());
    EXPECT_TRUE(mentions(r.status(), part)) << r.status().message();
}

TEST(OocJobsTest, BadPlansAndRecordsAreRefusedNamingTheFile) {
    const std::string dir = jobsDir("hostile");
    const std::string scan = jobsScan(dir, 30000);
    const std::string work = dir + "/work";
    ASSERT_GT(runPlan(scan, work, jobsOptions(work, 2), false), 0);
    const std::string plan_path = jobPlanPath(work);
    const std::string plan_text = lodbake_test::readTextFile(plan_path);
    lodbake::Diagnostics d;
    // A truncated plan.
    {
        std::ofstream(plan_path, std::ios::trunc) << plan_text.substr(0, plan_text.size() / 2);
        auto r = runJob(work, "pages", {}, d);
        ASSERT_FALSE(r.ok());
        EXPECT_TRUE(mentions(r.status(), plan_path)) << r.status().message();
        std::ofstream(plan_path, std::ios::trunc) << plan_text;
    }
    // A record whose job hash is not the plan's job (a stale or edited record).
    {
        const std::string record = jobRecordPath(work, "partition-0");
        const std::string text = lodbake_test::readTextFile(record);
        std::string edited = text;
        const size_t at = edited.find("\"job\": \"");
        ASSERT_NE(at, std::string::npos);
        edited[at + 8] = edited[at + 8] == '0' ? '1' : '0';
        std::ofstream(record, std::ios::trunc) << edited;
        auto r = runJob(work, "pages", {}, d);
        ASSERT_FALSE(r.ok());
        EXPECT_TRUE(mentions(r.status(), record)) << r.status().message();
        std::ofstream(record, std::ios::trunc) << text;
    }
    // The pages job hashes every input first: a merge file changed since its job ran is refused, and
    // the pages, the table and the record stay as they were.
    {
        const std::string pages_record = lodbake_test::readTextFile(jobRecordPath(work, "pages"));
        auto merge = readJobRecord(jobRecordPath(work, readJobPlan(plan_path)->jobs[readJobPlan(plan_path)->jobs.size() - 2].id));
        ASSERT_TRUE(merge.ok());
        ASSERT_EQ(merge->kind, JobKind::Merge);
        const std::string file = work + "/" + merge->output;
        const std::vector<uint8_t> good = fileBytes(file);
        std::vector<uint8_t> bad = good;
        bad[bad.size() / 3] ^= 0x10;
        ASSERT_TRUE(lodbake::writeFileAtomic(file, bad.data(), bad.size()).ok());
        auto r = runJob(work, "pages", {}, d);
        ASSERT_FALSE(r.ok());
        EXPECT_TRUE(mentions(r.status(), file)) << r.status().message();
        EXPECT_TRUE(mentions(r.status(), "corrupted")) << r.status().message();
        EXPECT_EQ(lodbake_test::readTextFile(jobRecordPath(work, "pages")), pages_record);
        ASSERT_TRUE(lodbake::writeFileAtomic(file, good.data(), good.size()).ok());
        EXPECT_TRUE(runJob(work, "pages", {}, d).ok());
    }
    // Hostile documents: every one refused, naming the file, on one line.
    const std::vector<std::string> hostile = {
        "",
        "{",
        "[]",
        "null",
        std::string(10000, '['),
        "{\"format\": \"lodbake-ooc-plan\", \"version\": 1}",
        "{\"format\": \"lodbake-ooc-plan\", \"version\": 2}",
        "{\"format\": \"other\", \"version\": 1}",
        "{\"format\": \"lodbake-ooc-job\", \"version\": 1, \"kind\": \"merge\"}",
        "{\"format\": \"lodbake-ooc-job\", \"version\": 1, \"kind\": 7}",
    };
    for (const std::string& text : hostile) {
        auto p = parseJobPlan(text, "plan.json");
        ASSERT_FALSE(p.ok()) << text.substr(0, 40);
        EXPECT_TRUE(mentions(p.status(), "plan.json")) << p.status().message();
        auto r = parseJobRecord(text, "job-x.json");
        ASSERT_FALSE(r.ok());
        EXPECT_TRUE(mentions(r.status(), "job-x.json")) << r.status().message();
    }
    // The real plan with one field made hostile at a time.
    const std::vector<std::pair<std::string, std::string>> edits = {
        {"\"id\": \"partition-0\"", "\"id\": \"../../etc/passwd\""},
        {"\"id\": \"partition-1\"", "\"id\": \"partition-0\""},
        {".lbpart\"", "/../x.lbpart\""},
        {"\"kind\": \"merge\"", "\"kind\": \"merges\""},
        {"\"max_levels\": ", "\"max_levels\": -"},
        {"\"complete\": true", "\"complete\": 1"},
        {"\"jobs\": [", "\"jobs\": [{\"id\": \"a\", \"kind\": \"merge\", \"inputs\": [{\"job\": \"b\"}, {\"job\": \"c\"}], \"cluster\": {}},"},
    };
    for (const auto& [from, to] : edits) {
        std::string text = plan_text;
        const size_t at = text.find(from);
        ASSERT_NE(at, std::string::npos) << from;
        text.replace(at, from.size(), to);
        auto p = parseJobPlan(text, "plan.json");
        EXPECT_FALSE(p.ok()) << to;
        if (!p.ok()) {
            EXPECT_TRUE(mentions(p.status(), "plan.json")) << p.status().message();
        }
    }
    // A plan whose partition jobs are not partition-0... (edited) is refused when planning on.
    {
        std::string text = plan_text;
        for (size_t at = text.find("\"partition-"); at != std::string::npos; at = text.find("\"partition-", at + 1))
            text.replace(at + 1, 9, "piece-xyz");
        text.replace(text.find("\"complete\": true"), 16, "\"complete\": false");
        ASSERT_TRUE(parseJobPlan(text, plan_path).ok());
        std::ofstream(plan_path, std::ios::trunc) << text;
        auto r = planOutOfCore(std::string(), work, jobsOptions(work, 2), d);
        ASSERT_FALSE(r.ok());
        EXPECT_TRUE(mentions(r.status(), plan_path)) << r.status().message();
        std::ofstream(plan_path, std::ios::trunc) << plan_text;
    }
    // A record round-trips.
    auto rec = readJobRecord(jobRecordPath(work, "pages"));
    ASSERT_TRUE(rec.ok()) << rec.status().message();
    EXPECT_EQ(jobRecordJson(*rec), lodbake_test::readTextFile(jobRecordPath(work, "pages")));
    auto plan = parseJobPlan(plan_text, plan_path);
    ASSERT_TRUE(plan.ok());
    EXPECT_EQ(jobPlanJson(*plan), plan_text);
}

TEST(OocJobsTest, PlanOptionsMustMatch) {
    const std::string dir = jobsDir("options");
    const std::string scan = jobsScan(dir, 30000);
    const std::string work = dir + "/work";
    lodbake::Diagnostics d;
    ASSERT_TRUE(planOutOfCore(scan, work, jobsOptions(work, 2), d).ok());
    OutOfCoreOptions other = jobsOptions(work, 2);
    other.leaf_triangles = 6000;
    auto r = planOutOfCore(scan, work, other, d);
    ASSERT_FALSE(r.ok());
    EXPECT_TRUE(mentions(r.status(), jobPlanPath(work))) << r.status().message();
}

// The protocol through the CLI, each --plan and --run-job its own process, on a scan of one
// partition at the default options: the same pages and table as buildOutOfCore.
TEST(OocJobsTest, CliJobsInSeparateProcessesGiveTheDriversBytes) {
    const std::string dir = jobsDir("cli");
    const std::string scan = jobsScan(dir, 20000);
    OutOfCoreOptions o;
    o.work_dir = dir + "/driver_work";
    const DriverBytes driver = driverBytes(scan, dir, o);
    ASSERT_FALSE(driver.pages.empty());
    const std::string work = dir + "/work";
    bool finished = false;
    for (int step = 0; step < 10 && !finished; ++step) {
        const lodbake_test::CliRun plan =
            lodbake_test::runLodbake({"bake", scan, "--clusters", "--plan", "--work-dir", work, "--memory-limit", "512"});
        ASSERT_EQ(plan.exit_code, 0) << plan.err;
        std::vector<std::string> lines;
        std::string line;
        for (char c : plan.out) {
            if (c != '\n') line += c;
            else lines.push_back(line), line.clear();
        }
        ASSERT_FALSE(lines.empty());
        EXPECT_EQ(lines[0], jobPlanPath(work));
        finished = lines.size() == 1;
        for (size_t i = 1; i < lines.size(); ++i) {
            const lodbake_test::CliRun job =
                lodbake_test::runLodbake(
                {"bake", "--run-job", lines[i], "--work-dir", work, "--memory-limit", "512", "--threads", "1"});
            ASSERT_EQ(job.exit_code, 0) << job.err;
            EXPECT_EQ(job.out, jobRecordPath(work, lines[i]) + "\n");
        }
    }
    ASSERT_TRUE(finished);
    auto result = plannedResult(work);
    ASSERT_TRUE(result.ok()) << result.status().message();
    EXPECT_EQ(fileBytes(result->output), driver.pages);
    EXPECT_EQ(result->table, driver.table);
    // Errors: one line naming the file, exit 1; usage errors exit 2.
    const lodbake_test::CliRun unknown = lodbake_test::runLodbake({"bake", "--run-job", "merge-7", "--work-dir", work});
    EXPECT_EQ(unknown.exit_code, 1);
    EXPECT_NE(unknown.err.find(jobPlanPath(work)), std::string::npos) << unknown.err;
    const lodbake_test::CliRun no_dir = lodbake_test::runLodbake({"bake", "--run-job", "pages"});
    EXPECT_EQ(no_dir.exit_code, 2);
    const lodbake_test::CliRun no_clusters = lodbake_test::runLodbake({"bake", scan, "--plan", "--work-dir", work});
    EXPECT_EQ(no_clusters.exit_code, 2);
    const lodbake_test::CliRun nowhere = lodbake_test::runLodbake({"bake", "--plan", "--clusters", "--work-dir", dir + "/none"});
    EXPECT_EQ(nowhere.exit_code, 2);
}

} // namespace
