// plan.json and the job records (lodbake/ooc/jobs.h) as JSON: nlohmann-json, its exceptions caught
// here. Every field is checked, so a truncated, edited or hostile file is an error naming it.
#include <cmath>
#include <exception>
#include <limits>
#include <set>

#include <nlohmann/json.hpp>

#include "lodbake/core/file_io.h"
#include "lodbake/core/hash.h"
#include "lodbake/core/json_limits.h"
#include "lodbake/ooc/jobs.h"
#include "lodrt/format.h"

namespace lodbake::ooc {

namespace {

using Json = nlohmann::json;

constexpr const char kPlanFormat[] = "lodbake-ooc-plan";
constexpr const char kRecordFormat[] = "lodbake-ooc-job";
// A plan nests five levels (plan, jobs, a job, its inputs, an input).
constexpr uint32_t kMaxDepth = 8;
constexpr uint64_t kMaxFileBytes = uint64_t(1) << 28;

// Never throws: a string that is not UTF-8 (an input path given as bytes) is written with
// replacement characters.
std::string dumpText(const Json& j, int indent = -1) {
    return j.dump(indent, ' ', false, Json::error_handler_t::replace);
}

// Errors as "<file>: <pointer>: expected ...".
struct Where {
    const std::string& path;
    std::string at;
    Where sub(const std::string& key) const { return {path, at + "/" + key}; }
    Where sub(size_t i) const { return {path, at + "/" + std::to_string(i)}; }
    Status expected(const std::string& what) const {
        return invalidInput(path + ": " + (at.empty() ? "/" : at) + ": expected " + what);
    }
};

Status checkKeys(const Json& o, const Where& w, const std::set<std::string>& known) {
    if (!o.is_object()) return w.expected("an object");
    for (auto it = o.begin(); it != o.end(); ++it)
        if (!known.count(it.key())) {
            const std::string quoted = dumpText(Json(it.key())); // control characters escaped: one line
            return w.expected("no key " + quoted + " (not in this version)");
        }
    for (const std::string& k : known)
        if (!o.contains(k)) return w.sub(k).expected("this key (missing)");
    return Status::okStatus();
}

Result<uint64_t> getU64(const Json& o, const char* key, const Where& w, uint64_t max) {
    const Json& v = o.at(key);
    if (!v.is_number_unsigned() || v.get<uint64_t>() > max)
        return w.sub(key).expected("an integer in [0, " + std::to_string(max) + "]");
    return v.get<uint64_t>();
}

Result<uint32_t> getU32(const Json& o, const char* key, const Where& w) {
    LODBAKE_ASSIGN_OR_RETURN(uint64_t v, getU64(o, key, w, 0xffffffffu));
    return uint32_t(v);
}

Result<double> getNumber(const Json& o, const char* key, const Where& w) {
    const Json& v = o.at(key);
    if (!v.is_number() || !std::isfinite(v.get<double>())) return w.sub(key).expected("a finite number");
    return v.get<double>();
}

Result<float> getFloat(const Json& o, const char* key, const Where& w) {
    LODBAKE_ASSIGN_OR_RETURN(double v, getNumber(o, key, w));
    if (std::fabs(v) > double(std::numeric_limits<float>::max())) return w.sub(key).expected("a float");
    return float(v);
}

Result<std::string> getString(const Json& o, const char* key, const Where& w) {
    const Json& v = o.at(key);
    if (!v.is_string()) return w.sub(key).expected("a string");
    const std::string s = v.get<std::string>();
    for (const char c : s)
        if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) return w.sub(key).expected("no control characters");
    return s;
}

bool isHex16(const std::string& s) {
    return s.size() == 16 && s.find_first_not_of("0123456789abcdef") == std::string::npos;
}

Result<uint64_t> getHash(const Json& o, const char* key, const Where& w) {
    LODBAKE_ASSIGN_OR_RETURN(std::string s, getString(o, key, w));
    if (!isHex16(s)) return w.sub(key).expected("16 lowercase hex digits");
    return std::stoull(s, nullptr, 16);
}

bool isJobId(const std::string& s) {
    return !s.empty() && s.size() <= 64 && s.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789-") == std::string::npos;
}

// A file of the work folder named by content hash: 16 hex digits and one of `extensions`.
bool isHashName(const std::string& s, std::initializer_list<const char*> extensions) {
    for (const char* ext : extensions) {
        const std::string e(ext);
        if (s.size() == 16 + e.size() && s.compare(16, e.size(), e) == 0 && isHex16(s.substr(0, 16))) return true;
    }
    return false;
}

Json clusterJson(const ClusterLodOptions& c) {
    Json j = Json::object();
    j["max_triangles"] = c.max_triangles;
    j["max_vertices"] = c.max_vertices;
    j["group_size"] = c.group_size;
    j["min_group_size"] = c.min_group_size;
    j["max_group_size"] = c.max_group_size;
    j["simplify_ratio"] = double(c.simplify_ratio);
    j["samples_per_triangle"] = double(c.samples_per_triangle);
    j["seed"] = c.seed;
    j["max_levels"] = c.max_levels;
    j["min_level_reduction"] = double(c.min_level_reduction);
    return j;
}

Result<ClusterLodOptions> parseCluster(const Json& j, const Where& w) {
    LODBAKE_RETURN_IF_ERROR(checkKeys(j, w,
                                      {"max_triangles", "max_vertices", "group_size", "min_group_size", "max_group_size",
                                       "simplify_ratio", "samples_per_triangle", "seed", "max_levels",
                                       "min_level_reduction"}));
    ClusterLodOptions c;
    LODBAKE_ASSIGN_OR_RETURN(c.max_triangles, getU32(j, "max_triangles", w));
    LODBAKE_ASSIGN_OR_RETURN(c.max_vertices, getU32(j, "max_vertices", w));
    LODBAKE_ASSIGN_OR_RETURN(c.group_size, getU32(j, "group_size", w));
    LODBAKE_ASSIGN_OR_RETURN(c.min_group_size, getU32(j, "min_group_size", w));
    LODBAKE_ASSIGN_OR_RETURN(c.max_group_size, getU32(j, "max_group_size", w));
    LODBAKE_ASSIGN_OR_RETURN(c.simplify_ratio, getFloat(j, "simplify_ratio", w));
    LODBAKE_ASSIGN_OR_RETURN(c.samples_per_triangle, getFloat(j, "samples_per_triangle", w));
    LODBAKE_ASSIGN_OR_RETURN(c.seed, getU64(j, "seed", w, std::numeric_limits<uint64_t>::max()));
    LODBAKE_ASSIGN_OR_RETURN(c.max_levels, getU32(j, "max_levels", w));
    LODBAKE_ASSIGN_OR_RETURN(c.min_level_reduction, getFloat(j, "min_level_reduction", w));
    return c;
}

Json jobJson(const JobSpec& job) {
    Json j = Json::object();
    j["id"] = job.id;
    j["kind"] = jobKindName(job.kind);
    Json inputs = Json::array();
    for (const JobInput& in : job.inputs) {
        Json i = Json::object();
        if (!in.file.empty()) i["file"] = in.file;
        else i["job"] = in.job;
        inputs.push_back(i);
    }
    j["inputs"] = inputs;
    if (job.kind == JobKind::Pages) j["position_bits"] = job.pack.position_bits;
    else j["cluster"] = clusterJson(job.cluster);
    return j;
}

uint64_t jobHash(const Json& canonical) {
    Hasher h;
    h.addString(dumpText(canonical));
    return h.digest();
}

Result<JobKind> parseKind(const Json& o, const Where& w) {
    LODBAKE_ASSIGN_OR_RETURN(std::string k, getString(o, "kind", w));
    for (JobKind kind : {JobKind::Partition, JobKind::Merge, JobKind::Pages})
        if (k == jobKindName(kind)) return kind;
    return w.sub("kind").expected("\"partition\", \"merge\" or \"pages\"");
}

Result<JobInput> parseInput(const Json& j, JobKind kind, const Where& w) {
    if (!j.is_object() || j.size() != 1) return w.expected("an object with one key, \"file\" or \"job\"");
    JobInput in;
    if (kind == JobKind::Partition) {
        if (!j.contains("file")) return w.expected("{\"file\": a partition file}");
        LODBAKE_ASSIGN_OR_RETURN(in.file, getString(j, "file", w));
        if (!isHashName(in.file, {lodrt::format::kPartitionExtension}))
            return w.sub("file").expected(std::string("<16 hex digits>") + lodrt::format::kPartitionExtension);
        return in;
    }
    if (!j.contains("job")) return w.expected("{\"job\": a job id}");
    LODBAKE_ASSIGN_OR_RETURN(in.job, getString(j, "job", w));
    if (!isJobId(in.job)) return w.sub("job").expected("a job id (a-z, 0-9 and '-')");
    return in;
}

Result<JobSpec> parseJob(const Json& j, const Where& w) {
    if (!j.is_object()) return w.expected("an object");
    if (!j.contains("kind")) return w.sub("kind").expected("this key (missing)");
    LODBAKE_ASSIGN_OR_RETURN(JobKind kind, parseKind(j, w));
    LODBAKE_RETURN_IF_ERROR(checkKeys(j, w, {"id", "kind", "inputs", kind == JobKind::Pages ? "position_bits" : "cluster"}));
    JobSpec job;
    job.kind = kind;
    LODBAKE_ASSIGN_OR_RETURN(job.id, getString(j, "id", w));
    if (!isJobId(job.id)) return w.sub("id").expected("a job id (a-z, 0-9 and '-', at most 64)");
    const Json& inputs = j.at("inputs");
    const size_t n = inputs.is_array() ? inputs.size() : 0;
    const bool count_ok = kind == JobKind::Partition ? n == 1 : kind == JobKind::Merge ? n == 2 : n >= 1;
    if (!inputs.is_array() || !count_ok)
        return w.sub("inputs").expected(kind == JobKind::Partition ? "an array of one input"
                                        : kind == JobKind::Merge   ? "an array of two inputs"
                                                                   : "a non-empty array");
    for (size_t i = 0; i < n; ++i) {
        LODBAKE_ASSIGN_OR_RETURN(JobInput in, parseInput(inputs[i], kind, w.sub("inputs").sub(i)));
        job.inputs.push_back(std::move(in));
    }
    if (kind == JobKind::Pages) {
        LODBAKE_ASSIGN_OR_RETURN(job.pack.position_bits, getU32(j, "position_bits", w));
    } else {
        LODBAKE_ASSIGN_OR_RETURN(job.cluster, parseCluster(j.at("cluster"), w.sub("cluster")));
    }
    job.hash = jobHash(jobJson(job));
    return job;
}

Result<Json> parseText(const std::string& text, const std::string& path) {
    const JsonDepthScan depth = scanJsonDepth(reinterpret_cast<const uint8_t*>(text.data()), text.size(), kMaxDepth);
    if (depth.is_too_deep)
        return invalidInput(path + ": byte " + std::to_string(depth.offset) + ": expected at most " +
                            std::to_string(kMaxDepth) + " levels of nested arrays and objects");
    try {
        return Json::parse(text);
    } catch (const Json::parse_error& e) {
        return invalidInput(path + ": not valid JSON at byte " + std::to_string(e.byte));
    } catch (const std::exception&) {
        return invalidInput(path + ": not valid JSON");
    }
}

Status checkHead(const Json& root, const char* format, const Where& w) {
    if (!root.is_object() || !root.contains("format") || !root.contains("version"))
        return w.expected(std::string("an object with \"format\": \"") + format + "\" and \"version\"");
    if (!root.at("format").is_string() || root.at("format").get<std::string>() != format)
        return w.sub("format").expected(std::string("\"") + format + "\"");
    if (!root.at("version").is_number_unsigned() || root.at("version").get<uint64_t>() != kJobListVersion)
        return w.sub("version").expected(std::to_string(kJobListVersion));
    return Status::okStatus();
}

Json planOptionsJson(const JobPlanOptions& o) {
    Json j = Json::object();
    j["leaf_triangles"] = o.leaf_triangles;
    j["merge_group_bytes"] = o.merge_group_bytes;
    j["sample_cap"] = o.sample_cap;
    j["cluster"] = clusterJson(o.cluster);
    j["position_bits"] = o.pack.position_bits;
    return j;
}

Result<JobPlanOptions> parsePlanOptions(const Json& j, const Where& w) {
    LODBAKE_RETURN_IF_ERROR(
        checkKeys(j, w, {"leaf_triangles", "merge_group_bytes", "sample_cap", "cluster", "position_bits"}));
    JobPlanOptions o;
    const uint64_t any = std::numeric_limits<uint64_t>::max();
    LODBAKE_ASSIGN_OR_RETURN(o.leaf_triangles, getU64(j, "leaf_triangles", w, any));
    LODBAKE_ASSIGN_OR_RETURN(o.merge_group_bytes, getU64(j, "merge_group_bytes", w, any));
    LODBAKE_ASSIGN_OR_RETURN(o.sample_cap, getU64(j, "sample_cap", w, any));
    LODBAKE_ASSIGN_OR_RETURN(o.cluster, parseCluster(j.at("cluster"), w.sub("cluster")));
    LODBAKE_ASSIGN_OR_RETURN(o.pack.position_bits, getU32(j, "position_bits", w));
    return o;
}

Result<JobPlan> parsePlanImpl(const Json& root, const std::string& path) {
    const Where w{path, ""};
    LODBAKE_RETURN_IF_ERROR(checkHead(root, kPlanFormat, w));
    LODBAKE_RETURN_IF_ERROR(checkKeys(root, w,
                                      {"format", "version", "input", "vertices", "triangles", "options", "merge_rounds",
                                       "complete", "jobs"}));
    JobPlan plan;
    const uint64_t any = std::numeric_limits<uint64_t>::max();
    LODBAKE_ASSIGN_OR_RETURN(plan.input, getString(root, "input", w));
    LODBAKE_ASSIGN_OR_RETURN(plan.vertex_count, getU64(root, "vertices", w, any));
    LODBAKE_ASSIGN_OR_RETURN(plan.triangle_count, getU64(root, "triangles", w, any));
    LODBAKE_ASSIGN_OR_RETURN(plan.options, parsePlanOptions(root.at("options"), w.sub("options")));
    LODBAKE_ASSIGN_OR_RETURN(plan.merge_rounds, getU32(root, "merge_rounds", w));
    if (!root.at("complete").is_boolean()) return w.sub("complete").expected("true or false");
    plan.complete = root.at("complete").get<bool>();
    const Json& jobs = root.at("jobs");
    if (!jobs.is_array() || jobs.empty()) return w.sub("jobs").expected("a non-empty array");
    std::set<std::string> ids;
    for (size_t i = 0; i < jobs.size(); ++i) {
        LODBAKE_ASSIGN_OR_RETURN(JobSpec job, parseJob(jobs[i], w.sub("jobs").sub(i)));
        // A job may depend only on a job listed before it: the plan's order is one that runs.
        for (size_t k = 0; k < job.inputs.size(); ++k)
            if (!job.inputs[k].job.empty() && !ids.count(job.inputs[k].job))
                return w.sub("jobs").sub(i).sub("inputs").sub(k).expected("a job listed before this one");
        if (!ids.insert(job.id).second) return w.sub("jobs").sub(i).sub("id").expected("an id no other job has");
        plan.jobs.push_back(std::move(job));
    }
    return plan;
}

Json sizeJson(const MergeInputSize& s) {
    Json j = Json::object();
    j["roots"] = s.roots;
    j["root_vertices"] = s.root_vertices;
    j["root_triangles"] = s.root_triangles;
    j["border_vertices"] = s.border_vertices;
    j["border_edges"] = s.border_edges;
    return j;
}

Result<MergeInputSize> parseSize(const Json& j, const Where& w) {
    LODBAKE_RETURN_IF_ERROR(checkKeys(j, w, {"roots", "root_vertices", "root_triangles", "border_vertices", "border_edges"}));
    MergeInputSize s;
    const uint64_t max = 0xffffffffu;
    LODBAKE_ASSIGN_OR_RETURN(s.roots, getU64(j, "roots", w, max));
    LODBAKE_ASSIGN_OR_RETURN(s.root_vertices, getU64(j, "root_vertices", w, max));
    LODBAKE_ASSIGN_OR_RETURN(s.root_triangles, getU64(j, "root_triangles", w, max));
    LODBAKE_ASSIGN_OR_RETURN(s.border_vertices, getU64(j, "border_vertices", w, max));
    LODBAKE_ASSIGN_OR_RETURN(s.border_edges, getU64(j, "border_edges", w, max));
    return s;
}

Json statsJson(const ClusterPackStats& s) {
    Json j = Json::object();
    j["table_bytes"] = uint64_t(s.table_bytes);
    j["page_bytes"] = uint64_t(s.page_bytes);
    j["run_bytes"] = uint64_t(s.run_bytes);
    j["page_count"] = uint64_t(s.page_count);
    j["max_page_bytes"] = uint64_t(s.max_page_bytes);
    j["lod0_triangles"] = uint64_t(s.lod0_triangles);
    j["lod0_page_bytes"] = uint64_t(s.lod0_page_bytes);
    j["cone_clusters"] = uint64_t(s.cone_clusters);
    j["quantization_error"] = s.quantization_error;
    return j;
}

Result<ClusterPackStats> parseStats(const Json& j, const Where& w) {
    LODBAKE_RETURN_IF_ERROR(checkKeys(j, w,
                                      {"table_bytes", "page_bytes", "run_bytes", "page_count", "max_page_bytes",
                                       "lod0_triangles", "lod0_page_bytes", "cone_clusters", "quantization_error"}));
    ClusterPackStats s;
    const uint64_t any = std::numeric_limits<uint64_t>::max();
    size_t* fields[] = {&s.table_bytes,    &s.page_bytes,     &s.run_bytes,       &s.page_count,
                        &s.max_page_bytes, &s.lod0_triangles, &s.lod0_page_bytes, &s.cone_clusters};
    const char* names[] = {"table_bytes",    "page_bytes",     "run_bytes",       "page_count",
                           "max_page_bytes", "lod0_triangles", "lod0_page_bytes", "cone_clusters"};
    for (size_t i = 0; i < 8; ++i) {
        LODBAKE_ASSIGN_OR_RETURN(uint64_t v, getU64(j, names[i], w, any));
        *fields[i] = size_t(v);
    }
    LODBAKE_ASSIGN_OR_RETURN(s.quantization_error, getNumber(j, "quantization_error", w));
    return s;
}

const char* outputExtension(JobKind kind) {
    return kind == JobKind::Partition ? lodrt::format::kPartitionLodExtension
           : kind == JobKind::Merge   ? lodrt::format::kPartitionMergeExtension
                                      : lodrt::format::kOocPagesExtension;
}

Result<JobRecord> parseRecordImpl(const Json& root, const std::string& path) {
    const Where w{path, ""};
    LODBAKE_RETURN_IF_ERROR(checkHead(root, kRecordFormat, w));
    if (!root.contains("kind")) return w.sub("kind").expected("this key (missing)");
    JobRecord r;
    LODBAKE_ASSIGN_OR_RETURN(r.kind, parseKind(root, w));
    std::set<std::string> keys = {"format", "version", "id", "kind", "job", "inputs", "output", "output_hash",
                                  "output_bytes"};
    if (r.kind == JobKind::Pages) keys.insert({"table", "table_hash", "table_bytes", "clusters", "stats"});
    else keys.insert("size");
    LODBAKE_RETURN_IF_ERROR(checkKeys(root, w, keys));
    LODBAKE_ASSIGN_OR_RETURN(r.id, getString(root, "id", w));
    if (!isJobId(r.id)) return w.sub("id").expected("a job id (a-z, 0-9 and '-', at most 64)");
    LODBAKE_ASSIGN_OR_RETURN(r.job_hash, getHash(root, "job", w));
    const Json& inputs = root.at("inputs");
    if (!inputs.is_array()) return w.sub("inputs").expected("an array of file names");
    for (size_t i = 0; i < inputs.size(); ++i) {
        if (!inputs[i].is_string() ||
            !isHashName(inputs[i].get<std::string>(),
                        {lodrt::format::kPartitionExtension, lodrt::format::kPartitionLodExtension,
                         lodrt::format::kPartitionMergeExtension}))
            return w.sub("inputs").sub(i).expected("a content-hash file name");
        r.inputs.push_back(inputs[i].get<std::string>());
    }
    const uint64_t any = std::numeric_limits<uint64_t>::max();
    LODBAKE_ASSIGN_OR_RETURN(r.output, getString(root, "output", w));
    LODBAKE_ASSIGN_OR_RETURN(r.output_hash, getHash(root, "output_hash", w));
    LODBAKE_ASSIGN_OR_RETURN(r.output_bytes, getU64(root, "output_bytes", w, any));
    if (r.output != hashToHex(r.output_hash) + outputExtension(r.kind))
        return w.sub("output").expected("the output hash followed by " + std::string(outputExtension(r.kind)));
    if (r.kind != JobKind::Pages) {
        LODBAKE_ASSIGN_OR_RETURN(r.size, parseSize(root.at("size"), w.sub("size")));
        return r;
    }
    LODBAKE_ASSIGN_OR_RETURN(r.table, getString(root, "table", w));
    LODBAKE_ASSIGN_OR_RETURN(r.table_hash, getHash(root, "table_hash", w));
    LODBAKE_ASSIGN_OR_RETURN(r.table_bytes, getU64(root, "table_bytes", w, any));
    if (r.table != hashToHex(r.table_hash) + lodrt::format::kOocTableExtension)
        return w.sub("table").expected(std::string("the table hash followed by ") + lodrt::format::kOocTableExtension);
    LODBAKE_ASSIGN_OR_RETURN(r.cluster_count, getU32(root, "clusters", w));
    LODBAKE_ASSIGN_OR_RETURN(r.stats, parseStats(root.at("stats"), w.sub("stats")));
    return r;
}

} // namespace

const char* jobKindName(JobKind kind) {
    return kind == JobKind::Partition ? "partition" : kind == JobKind::Merge ? "merge" : "pages";
}

const JobSpec* JobPlan::find(const std::string& id) const {
    for (const JobSpec& j : jobs)
        if (j.id == id) return &j;
    return nullptr;
}

uint64_t jobSpecHash(const JobSpec& job) {
    return jobHash(jobJson(job));
}

std::string jobPlanJson(const JobPlan& plan) {
    Json j = Json::object();
    j["format"] = kPlanFormat;
    j["version"] = kJobListVersion;
    j["input"] = plan.input;
    j["vertices"] = plan.vertex_count;
    j["triangles"] = plan.triangle_count;
    j["options"] = planOptionsJson(plan.options);
    j["merge_rounds"] = plan.merge_rounds;
    j["complete"] = plan.complete;
    Json jobs = Json::array();
    for (const JobSpec& job : plan.jobs) jobs.push_back(jobJson(job));
    j["jobs"] = jobs;
    return dumpText(j, 1) + "\n";
}

std::string jobRecordJson(const JobRecord& r) {
    Json j = Json::object();
    j["format"] = kRecordFormat;
    j["version"] = kJobListVersion;
    j["id"] = r.id;
    j["kind"] = jobKindName(r.kind);
    j["job"] = hashToHex(r.job_hash);
    j["inputs"] = r.inputs;
    j["output"] = r.output;
    j["output_hash"] = hashToHex(r.output_hash);
    j["output_bytes"] = r.output_bytes;
    if (r.kind != JobKind::Pages) {
        j["size"] = sizeJson(r.size);
    } else {
        j["table"] = r.table;
        j["table_hash"] = hashToHex(r.table_hash);
        j["table_bytes"] = r.table_bytes;
        j["clusters"] = r.cluster_count;
        j["stats"] = statsJson(r.stats);
    }
    return dumpText(j, 1) + "\n";
}

bool sameJobPlanOptions(const JobPlanOptions& a, const JobPlanOptions& b) {
    return planOptionsJson(a) == planOptionsJson(b);
}

Result<JobPlan> parseJobPlan(const std::string& text, const std::string& path) {
    LODBAKE_ASSIGN_OR_RETURN(Json root, parseText(text, path));
    try {
        return parsePlanImpl(root, path);
    } catch (const std::exception&) {
        return invalidInput(path + ": not a job plan of this version");
    }
}

Result<JobRecord> parseJobRecord(const std::string& text, const std::string& path) {
    LODBAKE_ASSIGN_OR_RETURN(Json root, parseText(text, path));
    try {
        return parseRecordImpl(root, path);
    } catch (const std::exception&) {
        return invalidInput(path + ": not a job record of this version");
    }
}

Result<JobPlan> readJobPlan(const std::string& path) {
    LODBAKE_ASSIGN_OR_RETURN(std::vector<uint8_t> bytes, readFileBytes(path, kMaxFileBytes));
    return parseJobPlan(std::string(bytes.begin(), bytes.end()), path);
}

Result<JobRecord> readJobRecord(const std::string& path) {
    LODBAKE_ASSIGN_OR_RETURN(std::vector<uint8_t> bytes, readFileBytes(path, kMaxFileBytes));
    return parseJobRecord(std::string(bytes.begin(), bytes.end()), path);
}

} // namespace lodbake::ooc
