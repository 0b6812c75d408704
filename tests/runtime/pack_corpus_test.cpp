// The lying-pack corpus (tests/malformed/pack/, written by its make_corpus.py): every NAME.glb is a
// pack a buggy or hostile baker could write, and NAME.expected the substring of the one-line error
// it must be refused with. lodrt refuses it on load (loadPack with its index scan, then
// buildModels), or, for lies inside the compressed streams that lodrt only decodes on demand,
// loddump's check (which decodes them with lodrt's decoders) does. Each pack must be refused with its
// own message: no other pack's expected substring may match it.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include <dirent.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include "lodrt/lodrt.h"

namespace {

const std::string kCorpus = LODRT_TEST_PACK_CORPUS;

bool endsWith(const std::string& s, const std::string& tail) {
    return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

bool readFile(const std::string& path, std::string* out) {
    std::FILE* file = std::fopen(path.c_str(), "rb");
    if (!file) return false;
    out->clear();
    char buf[4096];
    size_t n;
    while ((n = std::fread(buf, 1, sizeof(buf), file)) > 0) out->append(buf, n);
    std::fclose(file);
    return true;
}

std::vector<std::string> corpusFiles() {
    std::vector<std::string> names;
    DIR* dir = opendir(kCorpus.c_str());
    if (!dir) return names;
    while (const dirent* entry = readdir(dir)) {
        const std::string name = entry->d_name;
        if (name != "." && name != "..") names.push_back(name);
    }
    closedir(dir);
    std::sort(names.begin(), names.end());
    return names;
}

struct Verdict {
    std::string stage; // "loadPack", "buildModels", "loddump", or empty when nothing refused the pack
    std::string message;
};

// lodrt's load: what PackSource::openBytes does, with the index scan loadPack runs by default.
Verdict lodrtVerdict(const std::string& bytes) {
    char message[512] = {0};
    lodrt::Pack pack;
    const auto* data = reinterpret_cast<const uint8_t*>(bytes.data());
    if (lodrt::loadPack(data, bytes.size(), nullptr, &pack, message, sizeof(message)) != lodrt::Result::Ok)
        return {"loadPack", message};
    lodrt::ModelSet models;
    if (lodrt::buildModels(pack, nullptr, &models, message, sizeof(message)) != lodrt::Result::Ok)
        return {"buildModels", message};
    return {};
}

// loddump PATH: exit 1 and exactly one line "error: PATH: <pointer>: <message>" on stderr.
Verdict loddumpVerdict(const std::string& path) {
    const std::string err = std::string(LODRT_TEST_BINARY_DIR) + "/pack_corpus_" + std::to_string(::getpid()) + ".err";
    const std::string command = std::string("\"") + LODRT_TEST_LODDUMP + "\" \"" + path + "\" >/dev/null 2>\"" + err + "\"";
    const int status = std::system(command.c_str());
    std::string text;
    readFile(err, &text);
    std::remove(err.c_str());
    const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    if (code == 0) return {};
    const std::string prefix = "error: " + path + ": ";
    if (code != 1 || text.rfind(prefix, 0) != 0 || std::count(text.begin(), text.end(), '\n') != 1)
        return {"loddump", "<not one error line with exit code 1: exit " + std::to_string(code) + ": " + text + ">"};
    return {"loddump", text.substr(prefix.size(), text.size() - prefix.size() - 1)};
}

struct Case {
    std::string name;
    std::string expected;
    Verdict verdict;
};

std::vector<Case> runCorpus() {
    std::vector<Case> cases;
    for (const std::string& file : corpusFiles()) {
        if (!endsWith(file, ".glb")) continue;
        Case c;
        c.name = file.substr(0, file.size() - 4);
        std::string bytes;
        EXPECT_TRUE(readFile(kCorpus + "/" + file, &bytes)) << file;
        EXPECT_TRUE(readFile(kCorpus + "/" + c.name + ".expected", &c.expected)) << c.name << ".expected is missing";
        while (!c.expected.empty() && (c.expected.back() == '\n' || c.expected.back() == '\r')) c.expected.pop_back();
        c.verdict = lodrtVerdict(bytes);
        if (c.verdict.stage.empty()) c.verdict = loddumpVerdict(kCorpus + "/" + file);
        cases.push_back(c);
    }
    return cases;
}

TEST(PackCorpusTest, HoldsOnlyPacksWithTheirExpectedMessages) {
    const std::vector<std::string> files = corpusFiles();
    ASSERT_FALSE(files.empty()) << kCorpus << " is missing or empty";
    size_t packs = 0;
    std::map<std::string, std::string> expected_by_text;
    for (const std::string& file : files) {
        if (file == "make_corpus.py") continue;
        const bool is_pack = endsWith(file, ".glb"), is_expected = endsWith(file, ".expected");
        ASSERT_TRUE(is_pack || is_expected) << file << ": only NAME.glb, NAME.expected and make_corpus.py belong here";
        const std::string stem = file.substr(0, file.rfind('.'));
        const std::string partner = stem + (is_pack ? ".expected" : ".glb");
        EXPECT_TRUE(std::binary_search(files.begin(), files.end(), partner)) << file << " has no " << partner;
        if (!is_pack) continue;
        ++packs;
        std::string text;
        ASSERT_TRUE(readFile(kCorpus + "/" + stem + ".expected", &text));
        while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
        EXPECT_GE(text.size(), 12u) << stem << ": the expected message must name the element";
        EXPECT_EQ(text.find('\n'), std::string::npos) << stem << ": expected one line";
        const auto [it, inserted] = expected_by_text.emplace(text, stem);
        EXPECT_TRUE(inserted) << stem << " and " << it->second << " expect the same message '" << text << "'";
    }
    EXPECT_GE(packs, 30u);
}

TEST(PackCorpusTest, EveryPackIsRefusedWithItsOwnMessage) {
    const std::vector<Case> cases = runCorpus();
    ASSERT_GE(cases.size(), 30u);
    std::map<std::string, size_t> per_stage;
    std::map<std::string, std::string> by_message;
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        if (c.verdict.stage.empty()) {
            ADD_FAILURE() << "accepted by lodrt and by loddump";
            continue;
        }
        ++per_stage[c.verdict.stage];
        EXPECT_NE(c.verdict.message.find(c.expected), std::string::npos)
            << c.verdict.stage << " said '" << c.verdict.message << "', expected '" << c.expected << "'";
        const auto [it, inserted] = by_message.emplace(c.verdict.message, c.name);
        EXPECT_TRUE(inserted) << "same message as " << it->second << ": " << c.verdict.message;
        for (const Case& other : cases) {
            if (other.name == c.name) continue;
            EXPECT_EQ(c.verdict.message.find(other.expected), std::string::npos)
                << "the message '" << c.verdict.message << "' also matches " << other.name << "'s expected '"
                << other.expected << "'";
        }
    }
    std::string summary;
    for (const auto& [stage, count] : per_stage) summary += " " + stage + " " + std::to_string(count);
    std::printf("%zu packs, %zu distinct messages, refused by:%s\n", cases.size(), by_message.size(), summary.c_str());
}

// What the runtime does with a pack it accepted: open it as a PackSource and stream every level
// with the PFRep prefix. The lies left for loddump sit in compressed streams the levels do not
// need, so every level still arrives; a PFRep blob that openPfrep refuses fails its stream (and only
// that stream) in the streamer too.
TEST(PackCorpusTest, AcceptedPacksStreamAndFailOnlyTheirBadBlob) {
    size_t streamed = 0, failed_blobs = 0;
    for (const Case& c : runCorpus()) {
        if (c.verdict.stage != "loddump") continue;
        SCOPED_TRACE(c.name);
        std::string bytes;
        ASSERT_TRUE(readFile(kCorpus + "/" + c.name + ".glb", &bytes));
        lodrt::PackSource source;
        char message[256];
        ASSERT_EQ(source.openBytes(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size(), nullptr, message,
                                   sizeof(message)),
                  lodrt::Result::Ok)
            << message;
        lodrt::Streamer streamer;
        ASSERT_EQ(streamer.init(&source, nullptr, nullptr), lodrt::Result::Ok);
        const lodrt::ModelSet& models = source.models();
        std::vector<lodrt::ModelDemand> demand(models.modelCount(), lodrt::ModelDemand{0, 1.0f});
        for (int frame = 0; frame < 4 * int(lodrt::kMaxLevels) + 4; ++frame) streamer.update(demand.data());
        // The streamer reads the blob and the extension object's bufferView and levels; it must fail
        // the stream for a blob openPfrep refuses or a view that does not exist, and must not fail it
        // for a lie elsewhere. (Lies in fields it does not read, such as vertexCount, are loddump's.)
        const std::string& said = c.verdict.message;
        const bool bad_blob = said.find("LODBAKE_progressive_fans: stream fails to decode") != std::string::npos ||
                              said.find("LODBAKE_progressive_fans: bufferView") != std::string::npos;
        const bool elsewhere = said.find("LODBAKE_progressive_fans") == std::string::npos;
        bool any_failed = false;
        for (uint32_t m = 0; m < models.modelCount(); ++m) {
            for (uint32_t l = 0; l < models.model(m).level_count; ++l)
                EXPECT_EQ(streamer.state(m, l), lodrt::LevelState::Resident) << "model " << m << " level " << l;
            any_failed = any_failed || streamer.pfrepState(m) == lodrt::PfrepStreamState::Failed;
        }
        if (bad_blob) {
            EXPECT_TRUE(any_failed) << "the streamer accepted the blob loddump refused: " << said;
        }
        if (elsewhere) {
            EXPECT_FALSE(any_failed) << "the streamer failed a good blob: " << said;
        }
        ++streamed;
        failed_blobs += bad_blob;
    }
    EXPECT_GT(streamed, 0u);
    EXPECT_GT(failed_blobs, 0u);
}

} // namespace
