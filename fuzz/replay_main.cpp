// Without libFuzzer: runs LLVMFuzzerTestOneInput on every file of the folders (or files) given,
// in name order, the way CTest replays each target's corpus and its crash regressions; then,
// with --mutants N, on N inputs made from those by random mutations (no coverage guidance:
// a smoke that a gcc build can run in seconds, where bench/run_fuzz.sh fuzzes for real).
// A crash, an abort or a broken promise fails the process.
//
//   fuzz_NAME [--mutants N] [--seed S] PATH...
//
// The mutants depend only on the inputs, N and S (default 1), so a failing run fails again
// the same way; with PIC_FUZZ_MUTANT=FILE each mutant is written to FILE before it runs, so
// that the one that failed is left there.

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <string_view>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

namespace {

/// xorshift64*: small, fast and the same everywhere.
class Random {
public:
    explicit Random(uint64_t seed) : mState(seed * 0x9E3779B97F4A7C15ull + 1) {}
    uint64_t next() {
        mState ^= mState >> 12;
        mState ^= mState << 25;
        mState ^= mState >> 27;
        return mState * 0x2545F4914F6CDD1Dull;
    }
    /// In [0, n), n > 0.
    size_t below(size_t n) { return size_t(next() % n); }

private:
    uint64_t mState;
};

/// `input` changed by one to four of: a bit flipped, a byte set to a boundary value, a range
/// erased, random bytes inserted, a range repeated, a range copied from `other`, the end cut.
std::string mutate(std::string input, const std::string& other, Random& random) {
    static constexpr unsigned char kBoundaries[] = {0x00, 0x01, 0x7f, 0x80, 0xff, '"', '\\',
                                                    '{', '[', ',', '-', '9', 'e', '.'};
    const size_t count = 1 + random.below(4);
    for (size_t m = 0; m < count; ++m) {
        const size_t size = input.size();
        const size_t at = size ? random.below(size) : 0;
        const size_t length = size ? 1 + random.below(std::min<size_t>(size - at, 64)) : 0;
        switch (random.below(7)) {
        case 0:
            if (size) input[at] = char(input[at] ^ (1 << random.below(8)));
            break;
        case 1:
            if (size) input[at] = char(kBoundaries[random.below(sizeof kBoundaries)]);
            break;
        case 2:
            if (size) input.erase(at, length);
            break;
        case 3: {
            std::string bytes(1 + random.below(16), '\0');
            for (char& c : bytes) c = char(random.next());
            input.insert(at, bytes);
            break;
        }
        case 4:
            if (size) input.insert(at, input.substr(at, length));
            break;
        case 5:
            if (!other.empty()) {
                const size_t from = random.below(other.size());
                input.replace(at, length, other.substr(from, 1 + random.below(std::min<size_t>(other.size() - from, 64))));
            }
            break;
        default:
            if (size) input.resize(at);
            break;
        }
    }
    return input;
}

void run(const std::string& bytes) {
    LLVMFuzzerTestOneInput(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
}

}  // namespace

int main(int argc, char** argv) {
    namespace fs = std::filesystem;
    std::vector<fs::path> files;
    unsigned long long mutants = 0, seed = 1;
    for (int i = 1; i < argc; ++i) {
        const std::string_view arg(argv[i]);
        if ((arg == "--mutants" || arg == "--seed") && i + 1 < argc) {
            const std::string_view value(argv[++i]);
            if (value.empty() || value.size() > 18 ||
                value.find_first_not_of("0123456789") != std::string_view::npos) {
                std::fprintf(stderr, "replay: %s needs a whole number, got \"%s\"\n", argv[i - 1], argv[i]);
                return 2;
            }
            (arg == "--mutants" ? mutants : seed) = std::stoull(std::string(value));
            continue;
        }
        const fs::path path(argv[i]);
        if (fs::is_directory(path)) {
            for (const auto& entry : fs::directory_iterator(path))
                if (entry.is_regular_file()) files.push_back(entry.path());
        } else if (fs::is_regular_file(path)) {
            files.push_back(path);
        } else if (!fs::exists(path)) {
            std::fprintf(stderr, "replay: no %s, nothing from there\n", argv[i]);
        } else {
            std::fprintf(stderr, "replay: %s is neither a file nor a folder\n", argv[i]);
            return 2;
        }
    }
    std::sort(files.begin(), files.end());
    if (files.empty()) {
        std::fprintf(stderr, "replay: no input\n");
        return 2;
    }
    std::vector<std::string> inputs;
    for (const fs::path& file : files) {
        std::ifstream in(file, std::ios::binary);
        inputs.emplace_back(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
        std::fprintf(stderr, "replay: %s (%zu bytes)\n", file.filename().c_str(), inputs.back().size());
        run(inputs.back());
    }
    std::fprintf(stderr, "replay: %zu inputs, none crashed\n", inputs.size());
    if (mutants == 0) return 0;

    std::fprintf(stderr, "replay: %llu mutants, seed %llu\n", mutants, seed);
    const char* keep = std::getenv("PIC_FUZZ_MUTANT");
    Random random(seed);
    std::string previous;
    for (unsigned long long k = 0; k < mutants; ++k) {
        // Mutants of mutants too: every fourth starts from the one before.
        const std::string& base = (k % 4 == 3 && !previous.empty()) ? previous : inputs[size_t(k) % inputs.size()];
        std::string mutant = mutate(base, inputs[random.below(inputs.size())], random);
        if (keep) std::ofstream(keep, std::ios::binary | std::ios::trunc) << mutant;
        run(mutant);
        previous = std::move(mutant);
    }
    std::fprintf(stderr, "replay: %llu mutants, none crashed\n", mutants);
    return 0;
}
