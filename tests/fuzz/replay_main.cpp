// Runs a fuzz target's LLVMFuzzerTestOneInput over files without libFuzzer, so the crash
// regressions in tests/fuzz/regressions/ (and the malformed corpus) replay under ctest in every
// build, including the ASan/UBSan one. usage: fuzz_replay_<target> FILE_OR_DIR... Directories
// are read in sorted order; a crash, trap or sanitizer report fails the test, and so does finding
// no input at all (a mistyped path must not pass silently).
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <system_error>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

namespace {

bool runFile(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        std::fprintf(stderr, "cannot read %s\n", path.string().c_str());
        return false;
    }
    std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    // An exactly sized heap copy (data() of an empty vector may be null, as libFuzzer never passes).
    std::vector<uint8_t> exact(bytes.begin(), bytes.end());
    const uint8_t empty = 0;
    LLVMFuzzerTestOneInput(exact.empty() ? &empty : exact.data(), exact.size());
    return true;
}

} // namespace

int main(int argc, char** argv) {
    size_t count = 0;
    for (int i = 1; i < argc; ++i) {
        const std::filesystem::path arg(argv[i]);
        std::error_code ec;
        if (std::filesystem::is_directory(arg, ec)) {
            std::vector<std::filesystem::path> files;
            for (const auto& entry : std::filesystem::directory_iterator(arg, ec))
                if (entry.is_regular_file()) files.push_back(entry.path());
            std::sort(files.begin(), files.end());
            for (const auto& f : files) {
                if (!runFile(f)) return 1;
                ++count;
            }
        } else {
            if (!runFile(arg)) return 1;
            ++count;
        }
    }
    std::printf("replayed %zu inputs\n", count);
    return count == 0 ? 1 : 0;
}
