// The out-of-core job list (lodbake/ooc/jobs.h): the job functions the driver and runJob share, the
// incremental plan and one job run from files alone.
#include "lodbake/ooc/jobs.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <system_error>

#include <fcntl.h>
#include <unistd.h>

#include <tbb/task_arena.h>

#include "lodbake/core/file_io.h"
#include "lodbake/core/hash.h"
#include "lodbake/core/spill_file.h"
#include "lodrt/format.h"
#include "ooc/merge_rounds.h"

namespace lodbake::ooc {

namespace {

namespace fs = std::filesystem;

std::string baseName(const std::string& path) {
    return fs::path(path).filename().string();
}

bool exists(const std::string& path) {
    std::error_code ec;
    return fs::exists(path, ec);
}

uint64_t fileBytes(const std::string& path) {
    std::error_code ec;
    const uint64_t n = fs::file_size(path, ec);
    return ec ? 0 : n;
}

// The content hash of a whole file, read through a 1 MiB buffer.
Result<uint64_t> hashFile(const std::string& path) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return invalidInput(path + ": expected this input file: " + std::strerror(errno));
    Hasher hasher;
    std::vector<uint8_t> buffer(size_t(1) << 20);
    const uint64_t size = fileBytes(path);
    Status s = Status::okStatus();
    for (uint64_t off = 0; off < size && s.ok();) {
        const size_t n = size_t(std::min<uint64_t>(buffer.size(), size - off));
        s = readAt(fd, off, buffer.data(), n, path);
        hasher.addBytes(buffer.data(), n);
        off += n;
    }
    ::close(fd);
    if (!s.ok()) return s;
    return hasher.digest();
}

// An input named by content hash must hash to its name.
Status checkNamedHash(const std::string& path) {
    LODBAKE_ASSIGN_OR_RETURN(uint64_t h, hashFile(path));
    const std::string stem = fs::path(path).stem().string();
    if (stem != hashToHex(h))
        return invalidInput(path + ": content: expected bytes hashing to the file's name (" + stem + "), got " +
                            hashToHex(h) + ": the file is corrupted");
    return Status::okStatus();
}

std::string nodeJobId(const std::vector<TreeNode>& nodes, int node) {
    const TreeNode& n = nodes[size_t(node)];
    return n.left < 0 ? "partition-" + std::to_string(n.begin) : "merge-" + std::to_string(node);
}

size_t partitionJobCount(const JobPlan& plan) {
    size_t n = 0;
    for (const JobSpec& j : plan.jobs) n += j.kind == JobKind::Partition;
    return n;
}

// The record of listed job `id` when it is there and is that job's; nothing when it is missing;
// an error naming it when it is there but not the listed job's (a stale or edited record).
Result<bool> loadRecord(const std::string& work_dir, const JobPlan& plan, const std::string& id, JobRecord& out) {
    const std::string path = jobRecordPath(work_dir, id);
    if (!exists(path)) return false;
    LODBAKE_ASSIGN_OR_RETURN(out, readJobRecord(path));
    const JobSpec* spec = plan.find(id);
    if (!spec || out.id != id || out.kind != spec->kind || out.job_hash != spec->hash)
        return invalidInput(path + ": job: expected the record of job '" + id + "' as " + lodrt::format::kOocPlanFile +
                            " lists it (job hash " + hashToHex(spec ? spec->hash : 0) + "), got " +
                            hashToHex(out.job_hash) + ": run the job again");
    return true;
}

// A job input's record, which must be there, and its output file.
Result<JobRecord> requireRecord(const std::string& work_dir, const JobPlan& plan, const std::string& id) {
    JobRecord r;
    LODBAKE_ASSIGN_OR_RETURN(bool found, loadRecord(work_dir, plan, id, r));
    if (!found)
        return invalidInput(jobRecordPath(work_dir, id) + ": expected the record of job '" + id +
                            "', which must run first");
    const std::string output = joinPath(work_dir, r.output);
    if (!exists(output)) return invalidInput(output + ": expected the output of job '" + id + "' (missing)");
    return r;
}

// The merge tree of a plan's finished jobs (the pages job's inputs), from their records.
Result<MergeTree> treeOf(const std::string& work_dir, const JobPlan& plan, const JobSpec& pages) {
    MergeTree tree;
    std::map<std::string, std::string> output_of; // job id -> path
    for (const JobInput& in : pages.inputs) {
        const JobSpec* spec = plan.find(in.job);
        if (!spec || spec->kind == JobKind::Pages)
            return invalidInput(jobPlanPath(work_dir) + ": " + pages.id + ": expected partition and merge jobs as inputs");
        LODBAKE_ASSIGN_OR_RETURN(JobRecord r, requireRecord(work_dir, plan, in.job));
        const std::string path = joinPath(work_dir, r.output);
        output_of[in.job] = path;
        if (spec->kind == JobKind::Partition) {
            if (!tree.merges.empty())
                return invalidInput(jobPlanPath(work_dir) + ": " + pages.id + ": expected the partitions before the merges");
            tree.partitions.push_back(path);
            continue;
        }
        MergeFile m;
        m.path = path;
        m.content_hash = r.output_hash;
        for (int k = 0; k < 2; ++k) {
            const auto it = output_of.find(spec->inputs[size_t(k)].job);
            if (it == output_of.end())
                return invalidInput(jobPlanPath(work_dir) + ": " + in.job + ": expected inputs listed before it in " +
                                    pages.id);
            m.input_path[k] = it->second;
            m.input_kind[k] = plan.find(it->first)->kind == JobKind::Merge ? LodFileKind::Merge : LodFileKind::Partition;
        }
        m.root_count = uint32_t(r.size.roots);
        m.root_vertices = uint32_t(r.size.root_vertices);
        m.root_triangles = uint32_t(r.size.root_triangles);
        m.border_vertex_count = uint32_t(r.size.border_vertices);
        m.border_edge_count = uint32_t(r.size.border_edges);
        tree.merges.push_back(std::move(m));
    }
    if (tree.partitions.empty()) return invalidInput(jobPlanPath(work_dir) + ": " + pages.id + ": expected partitions");
    tree.top = tree.merges.empty() ? tree.partitions.back() : tree.merges.back().path;
    tree.merge_levels = plan.merge_rounds;
    return tree;
}

// Appends the next round's merge jobs, or the pages job after the top merge, when every listed job
// has its record. Returns whether it added any.
Result<bool> extendPlan(const std::string& work_dir, JobPlan& plan) {
    if (plan.complete) return false;
    // The tree's leaves are the jobs partition-0, partition-1, ... listed first (an edited plan may
    // say otherwise).
    const size_t partitions = partitionJobCount(plan);
    for (size_t i = 0; i < partitions; ++i)
        if (plan.jobs[i].kind != JobKind::Partition || plan.jobs[i].id != "partition-" + std::to_string(i))
            return invalidInput(jobPlanPath(work_dir) + ": /jobs/" + std::to_string(i) + ": expected job partition-" +
                                std::to_string(i));
    std::map<std::string, JobRecord> records;
    for (const JobSpec& job : plan.jobs) {
        JobRecord r;
        LODBAKE_ASSIGN_OR_RETURN(bool found, loadRecord(work_dir, plan, job.id, r));
        if (!found) return false; // the round is still running
        records[job.id] = std::move(r);
    }
    std::vector<TreeNode> nodes;
    buildTree(0, uint32_t(partitions), MergePairing::KdSiblings, nodes);
    for (size_t i = 0; i < nodes.size(); ++i) {
        const auto it = records.find(nodeJobId(nodes, int(i)));
        if (it == records.end()) continue;
        nodes[i].file = joinPath(work_dir, it->second.output);
        nodes[i].size = it->second.size;
    }
    if (!nodes[0].file.empty()) {
        JobSpec pages;
        pages.id = "pages";
        pages.kind = JobKind::Pages;
        for (const JobSpec& job : plan.jobs) pages.inputs.push_back({std::string(), job.id});
        pages.pack = plan.options.pack;
        pages.hash = jobSpecHash(pages);
        plan.jobs.push_back(std::move(pages));
        plan.complete = true;
        return true;
    }
    const MergeOptions mo = planMergeOptions(plan.options.cluster, plan.options.merge_group_bytes, 0);
    for (int picked : roundNodes(nodes, mo))
        for (const MergeStep& step : subtreeMerges(nodes, picked, roundLevels(picked, mo))) {
            JobSpec merge;
            merge.id = nodeJobId(nodes, step.node);
            merge.kind = JobKind::Merge;
            merge.inputs = {{std::string(), nodeJobId(nodes, nodes[size_t(step.node)].left)},
                            {std::string(), nodeJobId(nodes, nodes[size_t(step.node)].right)}};
            merge.cluster = plan.options.cluster;
            merge.cluster.max_levels = step.levels;
            merge.hash = jobSpecHash(merge);
            plan.jobs.push_back(std::move(merge));
        }
    ++plan.merge_rounds;
    return true;
}

Status writePlan(const std::string& work_dir, const JobPlan& plan) {
    const std::string text = jobPlanJson(plan);
    return writeFileAtomic(jobPlanPath(work_dir), text.data(), text.size());
}

JobPlanOptions planOptionsOf(const OutOfCoreOptions& o) {
    JobPlanOptions p;
    p.leaf_triangles = o.leaf_triangles;
    p.merge_group_bytes = o.merge_group_bytes;
    p.sample_cap = o.sample_cap;
    p.cluster = o.cluster;
    p.pack = o.pages.pack;
    return p;
}

// The first plan: the partitions and one job for each.
Result<JobPlan> newPlan(const std::string& input, const std::string& work_dir, const OutOfCoreOptions& options,
                        Diagnostics& diagnostics) {
    PartitionOptions po = outOfCorePartitionOptions(options);
    po.work_dir = work_dir;
    LODBAKE_ASSIGN_OR_RETURN(PartitionSet set, partitionMesh(input, po, diagnostics));
    if (set.partitions.empty()) return invalidInput(input + ": no triangles");
    JobPlan plan;
    plan.input = input;
    plan.vertex_count = set.vertex_count;
    plan.triangle_count = set.triangle_count;
    plan.options = planOptionsOf(options);
    for (size_t i = 0; i < set.partitions.size(); ++i) {
        JobSpec job;
        job.id = "partition-" + std::to_string(i);
        job.kind = JobKind::Partition;
        job.inputs = {{baseName(set.partitions[i].path), std::string()}};
        job.cluster = partitionJobCluster(options.cluster, set.partitions.size());
        job.hash = jobSpecHash(job);
        plan.jobs.push_back(std::move(job));
    }
    const Status s = writePlan(work_dir, plan);
    if (!s.ok()) {
        removePartitionFiles(set);
        return s;
    }
    return plan;
}

// The pages job: every input hashed against its name (they may come from other machines), the
// pages and the table written under their content hashes.
Status runPages(const std::string& work_dir, const JobPlan& plan, const JobSpec& spec, const JobRunOptions& options,
                JobRecord& record) {
    LODBAKE_ASSIGN_OR_RETURN(MergeTree tree, treeOf(work_dir, plan, spec));
    for (const std::string& p : tree.partitions) LODBAKE_RETURN_IF_ERROR(checkNamedHash(p));
    for (const MergeFile& m : tree.merges) LODBAKE_RETURN_IF_ERROR(checkNamedHash(m.path));
    for (const std::string& p : tree.partitions) record.inputs.push_back(baseName(p));
    for (const MergeFile& m : tree.merges) record.inputs.push_back(baseName(m.path));
    TreePagesOptions po;
    po.memory_limit_bytes = options.memory_limit_bytes;
    po.stream.pack = spec.pack;
    po.stream.pages_in_flight = options.pages_in_flight;
    po.stream.cancel = options.cancel;
    const std::string named_after = joinPath(work_dir, spec.id + lodrt::format::kOocPagesExtension);
    LODBAKE_ASSIGN_OR_RETURN(TreePagesResult pages, runPagesJob(tree, named_after, po));
    const std::vector<uint8_t>& table = pages.pack.extension.blobs[0];
    Hasher th;
    th.addBytes(table.data(), table.size());
    record.table_hash = th.digest();
    record.table = hashToHex(record.table_hash) + lodrt::format::kOocTableExtension;
    record.table_bytes = table.size();
    LODBAKE_RETURN_IF_ERROR(writeFileAtomic(joinPath(work_dir, record.table), table.data(), table.size()));
    const std::string spill = pages.pack.pages->tempPath();
    LODBAKE_ASSIGN_OR_RETURN(record.output_hash, hashFile(spill));
    record.output = hashToHex(record.output_hash) + lodrt::format::kOocPagesExtension;
    record.output_bytes = fileBytes(spill);
    if (options.cancel && options.cancel->load()) return ioError(named_after + ": job cancelled");
    const std::string output = joinPath(work_dir, record.output);
    if (::rename(spill.c_str(), output.c_str()) != 0) return ioError(output + ": cannot write the pages");
    record.cluster_count = pages.cluster_count;
    record.stats = pages.pack.stats;
    return Status::okStatus();
}

} // namespace

std::string jobPlanPath(const std::string& work_dir) {
    return joinPath(work_dir, lodrt::format::kOocPlanFile);
}

std::string jobRecordPath(const std::string& work_dir, const std::string& job_id) {
    return joinPath(work_dir,
                    std::string(lodrt::format::kOocJobRecordPrefix) + job_id + lodrt::format::kOocJobRecordSuffix);
}

PartitionOptions outOfCorePartitionOptions(const OutOfCoreOptions& o) {
    PartitionOptions po;
    po.work_dir = o.work_dir;
    po.memory_limit_bytes = o.memory_limit_bytes;
    po.threads = o.threads;
    po.read = o.read;
    po.sample_cap = o.sample_cap;
    po.cancel = o.cancel;
    po.build_bytes_per_triangle = kPartitionBuildBytesPerTriangle;
    po.leaf_triangles = o.leaf_triangles;
    return po;
}

ClusterLodOptions partitionJobCluster(const ClusterLodOptions& cluster, size_t partitions) {
    ClusterLodOptions c = cluster;
    if (partitions > 1) c.max_levels = std::min(cluster.max_levels, kLevelsPerJob);
    return c;
}

MergeOptions planMergeOptions(const ClusterLodOptions& cluster, uint64_t merge_group_bytes,
                              uint64_t memory_limit_bytes) {
    MergeOptions mo;
    mo.cluster = cluster;
    mo.group_bytes = merge_group_bytes;
    if (memory_limit_bytes > 0) mo.memory_limit_bytes = memory_limit_bytes;
    return mo;
}

Result<PartitionJobOutput> runPartitionJob(const std::string& partition_path, const std::string& work_dir,
                                           const ClusterLodOptions& cluster, uint64_t memory_limit_bytes,
                                           Diagnostics& diagnostics) {
    PartitionBuildOptions bo;
    bo.work_dir = work_dir;
    bo.memory_limit_bytes = memory_limit_bytes;
    bo.cluster = cluster;
    PartitionJobOutput out;
    LODBAKE_ASSIGN_OR_RETURN(out.file, buildPartition(partition_path, bo, diagnostics));
    // What the merge rounds are planned with: read from the file, as a merge of it will read it.
    LODBAKE_ASSIGN_OR_RETURN(out.size, mergeInputSize(out.file.path));
    return out;
}

Result<MergeFile> runMergeJob(const std::string& left, const std::string& right, const std::string& work_dir,
                              const ClusterLodOptions& cluster, uint64_t memory_limit_bytes, Diagnostics& diagnostics) {
    MergeOptions mo;
    mo.work_dir = work_dir;
    mo.memory_limit_bytes = memory_limit_bytes;
    mo.cluster = cluster;
    return mergePartitionLods(left, right, mo, diagnostics);
}

Result<TreePagesResult> runPagesJob(const MergeTree& tree, const std::string& output_path,
                                    const TreePagesOptions& options) {
    return writeTreeClusterPages(tree, output_path, options);
}

Result<JobPlan> planOutOfCore(const std::string& input, const std::string& work_dir, const OutOfCoreOptions& options,
                              Diagnostics& diagnostics) {
    if (work_dir.empty()) return invalidInput(input + ": out-of-core plan: no work folder given");
    if (options.merge_group_bytes == 0)
        return invalidInput(input + ": out-of-core plan: merge_group_bytes must be set (the limit must not shape the tree)");
    for (const char c : input + work_dir)
        if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
            return invalidInput("out-of-core plan: expected input and work folder paths without control characters");
    const std::string path = jobPlanPath(work_dir);
    if (!exists(path)) return newPlan(input, work_dir, options, diagnostics);
    LODBAKE_ASSIGN_OR_RETURN(JobPlan plan, readJobPlan(path));
    if (!sameJobPlanOptions(plan.options, planOptionsOf(options)))
        return invalidInput(path + ": options: expected this bake's options (the plan was made with others; use "
                                   "another work folder)");
    if (!input.empty() && input != plan.input)
        return invalidInput(path + ": input: expected " + plan.input + " (the plan's), got " + input +
                            " (use another work folder, or leave the input out)");
    LODBAKE_ASSIGN_OR_RETURN(bool added, extendPlan(work_dir, plan));
    if (added) LODBAKE_RETURN_IF_ERROR(writePlan(work_dir, plan));
    return plan;
}

namespace {

// runJob's work, inside the arena of its thread count.
Result<JobRecord> runJobInArena(const std::string& work_dir, const std::string& job_id, const JobRunOptions& options,
                                Diagnostics& diagnostics) {
    const std::string plan_path = jobPlanPath(work_dir);
    LODBAKE_ASSIGN_OR_RETURN(JobPlan plan, readJobPlan(plan_path));
    const JobSpec* spec = plan.find(job_id);
    if (!spec) return invalidInput(plan_path + ": jobs: expected a job with id '" + job_id + "'");
    if (options.cancel && options.cancel->load()) return ioError(plan_path + ": job " + job_id + " cancelled");
    JobRecord record;
    record.id = spec->id;
    record.kind = spec->kind;
    record.job_hash = spec->hash;
    if (spec->kind == JobKind::Pages) {
        LODBAKE_RETURN_IF_ERROR(runPages(work_dir, plan, *spec, options, record));
    } else {
        std::vector<std::string> paths;
        for (const JobInput& in : spec->inputs) {
            if (!in.file.empty()) {
                paths.push_back(joinPath(work_dir, in.file));
                if (!exists(paths.back())) return invalidInput(paths.back() + ": expected this input file (missing)");
                continue;
            }
            LODBAKE_ASSIGN_OR_RETURN(JobRecord r, requireRecord(work_dir, plan, in.job));
            paths.push_back(joinPath(work_dir, r.output));
        }
        for (const std::string& p : paths) record.inputs.push_back(baseName(p));
        std::string output;
        if (spec->kind == JobKind::Partition) {
            LODBAKE_ASSIGN_OR_RETURN(PartitionJobOutput out,
                                     runPartitionJob(paths[0], work_dir, spec->cluster, options.memory_limit_bytes,
                                                     diagnostics));
            output = out.file.path;
            record.output_hash = out.file.content_hash;
            record.size = out.size;
        } else {
            LODBAKE_ASSIGN_OR_RETURN(MergeFile m, runMergeJob(paths[0], paths[1], work_dir, spec->cluster,
                                                              options.memory_limit_bytes, diagnostics));
            output = m.path;
            record.output_hash = m.content_hash;
            record.size = {m.root_count, m.root_vertices, m.root_triangles, m.border_vertex_count, m.border_edge_count};
        }
        record.output = baseName(output);
        record.output_bytes = fileBytes(output);
    }
    const std::string text = jobRecordJson(record);
    LODBAKE_RETURN_IF_ERROR(writeFileAtomic(jobRecordPath(work_dir, job_id), text.data(), text.size()));
    return record;
}

} // namespace

Result<JobRecord> runJob(const std::string& work_dir, const std::string& job_id, const JobRunOptions& options,
                         Diagnostics& diagnostics) {
    tbb::task_arena arena(options.threads > 0 ? options.threads : int(tbb::task_arena::automatic));
    Result<JobRecord> result = internalError(job_id + ": job not run");
    arena.execute([&] { result = runJobInArena(work_dir, job_id, options, diagnostics); });
    return result;
}

JobProgress jobProgress(const std::string& work_dir, const JobPlan& plan) {
    JobProgress p;
    p.total = plan.jobs.size();
    std::map<std::string, bool> done;
    for (const JobSpec& job : plan.jobs) {
        JobRecord r;
        const Result<bool> found = loadRecord(work_dir, plan, job.id, r);
        done[job.id] = found.ok() && *found;
        if (done[job.id]) p.done.push_back(job.id);
    }
    for (const JobSpec& job : plan.jobs) {
        if (done[job.id]) continue;
        bool ready = true;
        for (const JobInput& in : job.inputs) ready = ready && (in.job.empty() || done[in.job]);
        if (ready) p.ready.push_back(job.id);
    }
    return p;
}

void removePlannedFiles(const std::string& work_dir) {
    const std::string plan_path = jobPlanPath(work_dir);
    const Result<JobPlan> plan = readJobPlan(plan_path);
    if (!plan.ok()) return;
    for (const JobSpec& job : plan->jobs) {
        for (const JobInput& in : job.inputs)
            if (!in.file.empty()) std::remove(joinPath(work_dir, in.file).c_str());
        const std::string record_path = jobRecordPath(work_dir, job.id);
        const Result<JobRecord> record = readJobRecord(record_path);
        if (record.ok()) {
            if (!record->output.empty()) std::remove(joinPath(work_dir, record->output).c_str());
            if (!record->table.empty()) std::remove(joinPath(work_dir, record->table).c_str());
        }
        std::remove(record_path.c_str());
    }
    std::remove(plan_path.c_str());
}

Result<OutOfCoreResult> plannedResult(const std::string& work_dir) {
    const std::string plan_path = jobPlanPath(work_dir);
    LODBAKE_ASSIGN_OR_RETURN(JobPlan plan, readJobPlan(plan_path));
    const JobSpec* pages = plan.complete ? &plan.jobs.back() : nullptr;
    if (!pages || pages->kind != JobKind::Pages)
        return invalidInput(plan_path + ": expected a complete plan (run --plan until it lists the pages job)");
    JobRecord record;
    LODBAKE_ASSIGN_OR_RETURN(bool found, loadRecord(work_dir, plan, pages->id, record));
    if (!found) return invalidInput(jobRecordPath(work_dir, pages->id) + ": expected the record of the pages job");
    OutOfCoreResult result;
    LODBAKE_ASSIGN_OR_RETURN(result.tree, treeOf(work_dir, plan, *pages));
    result.output = joinPath(work_dir, record.output);
    const std::string table = joinPath(work_dir, record.table);
    LODBAKE_RETURN_IF_ERROR(checkNamedHash(table));
    LODBAKE_ASSIGN_OR_RETURN(result.table, readFileBytes(table));
    result.stats = record.stats;
    result.cluster_count = record.cluster_count;
    result.triangle_count = plan.triangle_count;
    result.vertex_count = plan.vertex_count;
    result.partition_count = result.tree.partitions.size();
    result.merge_count = result.tree.merges.size();
    result.merge_rounds = plan.merge_rounds;
    return result;
}

} // namespace lodbake::ooc
