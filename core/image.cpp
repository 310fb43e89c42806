#include "core/image.h"

#include <algorithm>
#include <atomic>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <string_view>
#include <system_error>

#include <unistd.h>

#include <OpenImageIO/imageio.h>
#include <OpenImageIO/strutil.h>

#include "core/color.h"

namespace pic {

namespace {

/// The exact sRGB OETF (IEC 61966-2-1) of a linear value in [0, 1].
double srgbFromLinear(double linear) {
    return linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1.0 / 2.4) - 0.055;
}

/// The exact sRGB EOTF, inverse of srgbFromLinear.
double linearFromSrgb(double encoded) {
    return encoded <= 0.04045 ? encoded / 12.92 : std::pow((encoded + 0.055) / 1.055, 2.4);
}

/// One 8-bit sRGB code of a linear value scaled by exposure; NaN and negatives are black.
uint8_t srgb8(float linear, float exposure) {
    float v = linear * exposure;
    if (!(v > 0.0f)) return 0;
    return uint8_t(std::lround(255.0 * srgbFromLinear(std::min(v, 1.0f))));
}

/// OpenImageIO's message without the trailing newline it often carries.
std::string oiioMessage(std::string message) {
    while (!message.empty() && (message.back() == '\n' || message.back() == ' '))
        message.pop_back();
    return message.empty() ? "unknown OpenImageIO error" : message;
}

/// A temporary name beside `path` that keeps its extension ("out.exr" → "out.tmp.<pid>.<n>.exr"),
/// since OpenImageIO picks the file format from the extension; unique per process and call.
std::filesystem::path temporaryPath(const std::filesystem::path& path) {
    static std::atomic<uint64_t> counter{0};
    std::string name = fmt::format("{}.tmp.{}.{}{}", path.stem().string(), ::getpid(),
                                   counter.fetch_add(1), path.extension().string());
    return path.parent_path() / name;
}

/// Writes pixels of spec.format to `file`, whose extension picks the file format.
Result<void> writeWithOiio(const std::string& file, const std::string& shownPath,
                           const OIIO::ImageSpec& spec, const void* data) {
    std::unique_ptr<OIIO::ImageOutput> out = OIIO::ImageOutput::create(file);
    if (!out)
        return fail(ErrorCode::Io, "cannot write image {}: {}", shownPath,
                    oiioMessage(OIIO::geterror()));
    if (!out->open(file, spec))
        return fail(ErrorCode::Io, "cannot write image {}: {}", shownPath,
                    oiioMessage(out->geterror()));
    bool written = out->write_image(spec.format, data);
    // Close even after a failed write so the file handle is released before the cleanup.
    bool closed = out->close();
    if (!written || !closed)
        return fail(ErrorCode::Io, "cannot write image {}: {}", shownPath,
                    oiioMessage(out->geterror()));
    return {};
}

}  // namespace

Result<void> writeImage(const std::string& path, const Image& image, float exposure) {
    PIC_CHECK_EQ(image.pixels.size(), size_t{image.width} * image.height);
    if (image.width == 0 || image.height == 0)
        return fail(ErrorCode::InvalidInput, "cannot write image {}: it is empty ({}x{})", path,
                    image.width, image.height);
    if (!(std::isfinite(exposure) && exposure > 0.0f))
        return fail(ErrorCode::InvalidInput, "cannot write image {}: exposure {} must be > 0", path,
                    exposure);

    std::filesystem::path target(path);
    std::string extension = OIIO::Strutil::lower(target.extension().string());
    bool png = extension == ".png";
    if (!png && extension != ".exr" && extension != ".hdr" && extension != ".tif" &&
        extension != ".tiff")
        return fail(
            ErrorCode::InvalidInput,
            "cannot write image {}: unknown extension \"{}\" (use .exr, .png, .hdr or .tif)", path,
            extension);

    OIIO::ImageSpec spec(int(image.width), int(image.height), 3,
                         png ? OIIO::TypeDesc::UINT8 : OIIO::TypeDesc::FLOAT);
    spec.attribute("oiio:ColorSpace", png ? "sRGB" : "Linear");
    std::vector<uint8_t> encoded;
    const void* data = image.pixels.data();
    if (png) {
        encoded.resize(image.pixels.size() * 3);
        for (size_t i = 0; i < image.pixels.size(); ++i)
            for (int c = 0; c < 3; ++c)
                encoded[3 * i + size_t(c)] = srgb8(image.pixels[i][c], exposure);
        data = encoded.data();
    }

    // Readers (a watching script, a chart) never see a half-written file: write beside the
    // target, then rename over it, which is atomic within one file system.
    std::filesystem::path temporary = temporaryPath(target);
    std::error_code ignored;
    if (auto written = writeWithOiio(temporary.string(), path, spec, data); !written) {
        std::filesystem::remove(temporary, ignored);
        return written;
    }
    std::error_code renameError;
    std::filesystem::rename(temporary, target, renameError);
    if (renameError) {
        std::filesystem::remove(temporary, ignored);
        return fail(ErrorCode::Io, "cannot write image {}: {}", path, renameError.message());
    }
    return {};
}

Result<Image> readImage(const std::string& path) {
    std::error_code ec;
    if (!std::filesystem::exists(path, ec))
        return fail(ErrorCode::NotFound, "image {} does not exist", path);
    // Alpha is dropped below, so colour must come as stored, not premultiplied by alpha.
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    std::unique_ptr<OIIO::ImageInput> in = OIIO::ImageInput::open(path, &config);
    if (!in)
        return fail(ErrorCode::Corrupt, "cannot read image {}: {}", path,
                    oiioMessage(OIIO::geterror()));
    const OIIO::ImageSpec& spec = in->spec();
    if (spec.width < 1 || spec.height < 1 || spec.nchannels < 1)
        return fail(ErrorCode::Corrupt, "image {} has no pixels ({}x{}, {} channels)", path,
                    spec.width, spec.height, spec.nchannels);
    if (spec.depth != 1)
        return fail(ErrorCode::Unsupported, "image {} is a volume ({} slices)", path, spec.depth);

    size_t channels = size_t(spec.nchannels);
    size_t pixelCount = size_t(spec.width) * size_t(spec.height);
    std::vector<float> values(pixelCount * channels);
    // OpenImageIO converts any stored type to float, integers normalised to [0, 1].
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, values.data()))
        return fail(ErrorCode::Corrupt, "cannot read image {}: {}", path,
                    oiioMessage(in->geterror()));

    // PNG and JPEG hold sRGB-encoded values by convention; other formats say so if they do.
    std::string format = in->format_name();
    bool srgb = format == "png" || format == "jpeg" ||
                OIIO::Strutil::iequals(spec.get_string_attribute("oiio:ColorSpace"), "sRGB");

    Image image(uint32_t(spec.width), uint32_t(spec.height));
    for (size_t i = 0; i < pixelCount; ++i) {
        const float* pixel = &values[i * channels];
        // One or two channels are grey (plus alpha); from three on, alpha and the rest are dropped.
        glm::vec3 rgb =
            channels < 3 ? glm::vec3(pixel[0]) : glm::vec3(pixel[0], pixel[1], pixel[2]);
        if (srgb)
            for (int c = 0; c < 3; ++c) rgb[c] = float(linearFromSrgb(rgb[c]));
        image.pixels[i] = rgb;
    }
    return image;
}

Result<glm::uvec2> parseImageSize(const std::string& text) {
    auto invalid = [&] {
        return fail(ErrorCode::InvalidInput,
                    "image size must be WxH with W and H in 1..{} (e.g. 640x480), got \"{}\"",
                    kMaxImageSide, text);
    };
    size_t x = text.find('x');
    if (x == std::string::npos) return invalid();
    glm::uvec2 size;
    for (int axis = 0; axis < 2; ++axis) {
        std::string_view digits =
            axis == 0 ? std::string_view(text).substr(0, x) : std::string_view(text).substr(x + 1);
        auto [end, error] =
            std::from_chars(digits.data(), digits.data() + digits.size(), size[axis]);
        if (digits.empty() || error != std::errc() || end != digits.data() + digits.size() ||
            size[axis] < 1 || size[axis] > kMaxImageSide)
            return invalid();
    }
    return size;
}

Result<ImageError> compareImages(const Image& image, const Image& reference) {
    if (image.width != reference.width || image.height != reference.height)
        return fail(ErrorCode::InvalidInput, "image is {}x{} but the reference is {}x{}",
                    image.width, image.height, reference.width, reference.height);
    if (reference.pixels.empty())
        return fail(ErrorCode::InvalidInput, "cannot compare empty images");

    // Doubles throughout: a 4K image sums 25 million values.
    double squaredError = 0.0, referenceSum = 0.0;
    double imageLuminance = 0.0, referenceLuminance = 0.0;
    glm::dvec3 imageChannel(0.0), referenceChannel(0.0);
    for (uint32_t y = 0; y < image.height; ++y) {
        for (uint32_t x = 0; x < image.width; ++x) {
            const glm::vec3& a = image.at(x, y);
            const glm::vec3& b = reference.at(x, y);
            // A single NaN would silently turn every metric into NaN; name the pixel instead.
            if (!std::isfinite(a.x + a.y + a.z))
                return fail(ErrorCode::InvalidInput,
                            "image has a non-finite value at pixel ({}, {})", x, y);
            if (!std::isfinite(b.x + b.y + b.z))
                return fail(ErrorCode::InvalidInput,
                            "reference has a non-finite value at pixel ({}, {})", x, y);
            for (int c = 0; c < 3; ++c) {
                double d = double(a[c]) - double(b[c]);
                squaredError += d * d;
                referenceSum += b[c];
            }
            imageLuminance += luminance(a);
            referenceLuminance += luminance(b);
            imageChannel += glm::dvec3(a);
            referenceChannel += glm::dvec3(b);
        }
    }
    double valueCount = 3.0 * double(reference.pixels.size());
    double referenceMean = referenceSum / valueCount;
    if (!(referenceMean > 0.0) || !(referenceLuminance > 0.0))
        return fail(ErrorCode::InvalidInput,
                    "reference mean is {} and its mean luminance {}: relative error needs both > 0",
                    referenceMean, referenceLuminance / double(reference.pixels.size()));
    ImageError error;
    error.rmse = std::sqrt(squaredError / valueCount);
    error.relativeRmse = error.rmse / referenceMean;
    error.meanRatio = imageLuminance / referenceLuminance;
    for (int c = 0; c < 3; ++c) error.channelRatio[c] = referenceChannel[c] > 0.0 ? imageChannel[c] / referenceChannel[c] : 0.0;
    return error;
}

Result<Image> blockAverage(const Image& image, uint32_t block) {
    if (block == 0) return fail(ErrorCode::InvalidInput, "block size 0: blocks need ≥ 1 pixel");
    if (image.pixels.empty()) return fail(ErrorCode::InvalidInput, "cannot average an empty image");
    Image averaged((image.width + block - 1) / block, (image.height + block - 1) / block);
    for (uint32_t by = 0; by < averaged.height; ++by)
        for (uint32_t bx = 0; bx < averaged.width; ++bx) {
            glm::dvec3 sum(0.0);
            uint32_t count = 0;
            for (uint32_t y = by * block; y < std::min(image.height, (by + 1) * block); ++y)
                for (uint32_t x = bx * block; x < std::min(image.width, (bx + 1) * block); ++x) {
                    sum += glm::dvec3(image.at(x, y));
                    ++count;
                }
            averaged.at(bx, by) = glm::vec3(sum / double(count));
        }
    return averaged;
}

Result<double> blotchIndex(const Image& image, const Image& reference, uint32_t block) {
    PIC_TRY_ASSIGN(const ImageError whole, compareImages(image, reference));
    if (!(whole.meanRatio > 0.0))
        return fail(ErrorCode::InvalidInput, "image mean luminance ratio is {}: nothing to scale",
                    whole.meanRatio);
    PIC_TRY_ASSIGN(Image scaled, blockAverage(image, block));
    for (glm::vec3& p : scaled.pixels) p /= float(whole.meanRatio);
    PIC_TRY_ASSIGN(const Image referenceBlocks, blockAverage(reference, block));
    PIC_TRY_ASSIGN(const ImageError blocks, compareImages(scaled, referenceBlocks));
    return blocks.relativeRmse;
}

}  // namespace pic
