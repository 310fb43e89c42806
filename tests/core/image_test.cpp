#include "core/image.h"

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include <unistd.h>

#include <gtest/gtest.h>
#include <stb/stb_image.h>
#include <stb/stb_image_write.h>

namespace pic {
namespace {

namespace fs = std::filesystem;

/// A fresh directory per test, removed afterwards.
class ImageFiles : public ::testing::Test {
protected:
    void SetUp() override {
        mDir = fs::temp_directory_path() /
               fmt::format("pic_image_test_{}_{}", ::getpid(),
                           ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(mDir);
        fs::create_directories(mDir);
    }
    void TearDown() override { fs::remove_all(mDir); }
    std::string file(const std::string& name) const { return (mDir / name).string(); }

    fs::path mDir;
};

/// The 8-bit channels of a PNG exactly as stored, read by an independent decoder.
std::vector<uint8_t> rawPng(const std::string& path, int& width, int& height) {
    int channels = 0;
    stbi_uc* data = stbi_load(path.c_str(), &width, &height, &channels, 3);
    EXPECT_NE(data, nullptr) << path;
    if (!data) return {};
    std::vector<uint8_t> bytes(data, data + size_t(width) * size_t(height) * 3);
    stbi_image_free(data);
    return bytes;
}

/// The linear value of an 8-bit sRGB code by the IEC 61966-2-1 formula.
float srgbDecode(int code) {
    double v = code / 255.0;
    return float(v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4));
}

double srgbEncode(double linear) {
    return linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1.0 / 2.4) - 0.055;
}

Image filled(uint32_t width, uint32_t height, const glm::vec3& value) {
    Image image(width, height);
    for (glm::vec3& pixel : image.pixels) pixel = value;
    return image;
}

TEST_F(ImageFiles, ExrRoundTripIsBitExact) {
    Image image(7, 5);
    for (uint32_t y = 0; y < image.height; ++y)
        for (uint32_t x = 0; x < image.width; ++x)
            image.at(x, y) = {0.1f * float(x) + 1e-3f * float(y), std::ldexp(1.7f, int(x) * 9 - 30),
                              -0.33f * float(y) + 1.0f / 3.0f};
    image.at(3, 2) = {1e-40f, 65504.0f, 3.4e38f};  // a subnormal, the half maximum, near FLT_MAX
    std::string path = file("round.exr");
    auto written = writeImage(path, image);
    ASSERT_TRUE(written) << written.error().message;
    auto read = readImage(path);
    ASSERT_TRUE(read) << read.error().message;
    ASSERT_EQ(read->width, image.width);
    ASSERT_EQ(read->height, image.height);
    EXPECT_EQ(std::memcmp(read->pixels.data(), image.pixels.data(),
                          image.pixels.size() * sizeof(glm::vec3)),
              0);
    // Row 0 is the top: a non-symmetric pixel lands where it was written.
    EXPECT_EQ(read->at(6, 0), image.at(6, 0));
}

TEST_F(ImageFiles, PngEncodesExactSrgbOfClampedExposedValues) {
    Image image(8, 1);
    image.at(0, 0) = glm::vec3(0.5f);
    image.at(1, 0) = {0.0f, 1.0f, 2.0f};
    image.at(2, 0) = {-1.0f, std::numeric_limits<float>::quiet_NaN(), 0.001f};
    image.at(3, 0) = {0.25f, 0.2f, 0.8f};
    std::string path = file("codes.png");
    auto written = writeImage(path, image);
    ASSERT_TRUE(written) << written.error().message;
    int width = 0, height = 0;
    std::vector<uint8_t> bytes = rawPng(path, width, height);
    ASSERT_EQ(width, 8);
    ASSERT_EQ(height, 1);
    // 1.055·0.5^(1/2.4) − 0.055 = 0.7354 → 187.5 → 188.
    EXPECT_EQ(bytes[0], 188);
    EXPECT_EQ(bytes[3], 0);
    EXPECT_EQ(bytes[4], 255);
    EXPECT_EQ(bytes[5], 255);  // clamped
    EXPECT_EQ(bytes[6], 0);    // negative → black
    EXPECT_EQ(bytes[7], 0);    // NaN → black
    EXPECT_EQ(bytes[8], 3);    // linear segment: 12.92·0.001·255 = 3.29
    for (int c = 0; c < 3; ++c)
        EXPECT_EQ(bytes[9 + size_t(c)], std::lround(255.0 * srgbEncode(image.at(3, 0)[c])));

    // Exposure scales before the clamp: 0.25 at exposure 2 is the 0.5 above, 0.8 clamps.
    auto exposed = writeImage(path, image, 2.0f);
    ASSERT_TRUE(exposed) << exposed.error().message;
    bytes = rawPng(path, width, height);
    EXPECT_EQ(bytes[9], 188);
    EXPECT_EQ(bytes[11], 255);
}

TEST_F(ImageFiles, PngRoundTripWithinQuantisation) {
    Image image(16, 16);
    for (uint32_t y = 0; y < 16; ++y)
        for (uint32_t x = 0; x < 16; ++x)
            image.at(x, y) = {float(x) / 15.0f, float(y * y) / 225.0f, 0.002f * float(x + y)};
    std::string path = file("round.png");
    ASSERT_TRUE(writeImage(path, image));
    auto read = readImage(path);
    ASSERT_TRUE(read) << read.error().message;
    ASSERT_EQ(read->width, 16u);
    for (size_t i = 0; i < image.pixels.size(); ++i)
        for (int c = 0; c < 3; ++c) {
            // Within half a code step of the original in the encoded domain.
            double original = srgbEncode(image.pixels[i][c]);
            double back = srgbEncode(read->pixels[i][c]);
            EXPECT_NEAR(back, original, 0.5 / 255.0 + 1e-6) << "pixel " << i << " channel " << c;
        }
}

TEST_F(ImageFiles, ReadsGreyAndRgbaPngAsLinearRgb) {
    // Grey: one channel becomes three equal ones.
    std::vector<uint8_t> grey = {0, 188, 255, 10};
    std::string greyPath = file("grey.png");
    ASSERT_TRUE(stbi_write_png(greyPath.c_str(), 2, 2, 1, grey.data(), 2));
    auto greyImage = readImage(greyPath);
    ASSERT_TRUE(greyImage) << greyImage.error().message;
    ASSERT_EQ(greyImage->width, 2u);
    for (size_t i = 0; i < 4; ++i)
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(greyImage->pixels[i][c], srgbDecode(grey[i]), 1e-6f) << i;

    // RGBA: the alpha channel is dropped, colour is not premultiplied by it.
    std::vector<uint8_t> rgba = {255, 128, 0, 0, 20, 40, 60, 255};
    std::string rgbaPath = file("rgba.png");
    ASSERT_TRUE(stbi_write_png(rgbaPath.c_str(), 2, 1, 4, rgba.data(), 8));
    auto rgbaImage = readImage(rgbaPath);
    ASSERT_TRUE(rgbaImage) << rgbaImage.error().message;
    ASSERT_EQ(rgbaImage->pixels.size(), 2u);
    for (size_t i = 0; i < 2; ++i)
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(rgbaImage->pixels[i][c], srgbDecode(rgba[4 * i + size_t(c)]), 1e-6f);
}

TEST_F(ImageFiles, WriteFailuresAreIoErrorsAndLeaveNoTemporaryFile) {
    Image image = filled(4, 4, glm::vec3(0.5f));
    std::string missing = file("missing/out.exr");
    auto result = writeImage(missing, image);
    ASSERT_FALSE(result);
    EXPECT_EQ(result.error().code, ErrorCode::Io);
    EXPECT_NE(result.error().message.find(missing), std::string::npos) << result.error().message;

    // The temporary file is written but the rename onto a directory fails: it must go again.
    fs::create_directory(mDir / "taken.png");
    auto blocked = writeImage(file("taken.png"), image);
    ASSERT_FALSE(blocked);
    EXPECT_EQ(blocked.error().code, ErrorCode::Io);
    EXPECT_NE(blocked.error().message.find("taken.png"), std::string::npos);
    for (const fs::directory_entry& entry : fs::directory_iterator(mDir))
        EXPECT_EQ(entry.path().filename(), "taken.png") << "left behind: " << entry.path();
}

TEST_F(ImageFiles, WriteReplacesAnExistingFile) {
    std::string path = file("replaced.exr");
    ASSERT_TRUE(writeImage(path, filled(2, 2, glm::vec3(1.0f))));
    ASSERT_TRUE(writeImage(path, filled(3, 1, glm::vec3(2.0f))));
    auto read = readImage(path);
    ASSERT_TRUE(read) << read.error().message;
    EXPECT_EQ(read->width, 3u);
    EXPECT_EQ(read->at(2, 0), glm::vec3(2.0f));
    // Only the file itself remains.
    EXPECT_EQ(std::distance(fs::directory_iterator(mDir), fs::directory_iterator()), 1);
}

TEST_F(ImageFiles, RejectsBadRequestsAndBadFiles) {
    Image image = filled(2, 2, glm::vec3(0.5f));
    auto extension = writeImage(file("out.bmpx"), image);
    ASSERT_FALSE(extension);
    EXPECT_EQ(extension.error().code, ErrorCode::InvalidInput);
    EXPECT_NE(extension.error().message.find(".bmpx"), std::string::npos);
    auto empty = writeImage(file("empty.exr"), Image());
    ASSERT_FALSE(empty);
    EXPECT_EQ(empty.error().code, ErrorCode::InvalidInput);
    auto exposure = writeImage(file("dark.png"), image, -1.0f);
    ASSERT_FALSE(exposure);
    EXPECT_EQ(exposure.error().code, ErrorCode::InvalidInput);

    auto missing = readImage(file("nothing.exr"));
    ASSERT_FALSE(missing);
    EXPECT_EQ(missing.error().code, ErrorCode::NotFound);
    EXPECT_NE(missing.error().message.find("nothing.exr"), std::string::npos);
    std::ofstream(file("garbage.exr")) << "not an image";
    auto garbage = readImage(file("garbage.exr"));
    ASSERT_FALSE(garbage);
    EXPECT_EQ(garbage.error().code, ErrorCode::Corrupt);
    EXPECT_NE(garbage.error().message.find("garbage.exr"), std::string::npos);
}

TEST(ImageSize, ParsesWidthByHeight) {
    auto size = parseImageSize("640x480");
    ASSERT_TRUE(size) << size.error().message;
    EXPECT_EQ(*size, glm::uvec2(640, 480));
    EXPECT_EQ(parseImageSize("1x16384").value(), glm::uvec2(1, 16384));
    for (const char* bad : {"", "640", "x480", "640x", "0x480", "640x0", "16385x2", "-1x5",
                            "64x48x2", " 64x48", "64X48", "6.4x48", "99999999999x1"}) {
        auto parsed = parseImageSize(bad);
        ASSERT_FALSE(parsed) << bad;
        EXPECT_EQ(parsed.error().code, ErrorCode::InvalidInput);
        EXPECT_NE(parsed.error().message.find(fmt::format("\"{}\"", bad)), std::string::npos)
            << parsed.error().message;
    }
}

TEST(CompareImages, MetricsOfHandMadeImages) {
    Image reference = filled(2, 1, glm::vec3(1.0f));
    Image image = reference;
    image.at(0, 0) = {2.0f, 1.0f, 1.0f};
    auto error = compareImages(image, reference);
    ASSERT_TRUE(error) << error.error().message;
    // One value of six is off by 1; the reference mean is 1.
    EXPECT_NEAR(error->rmse, std::sqrt(1.0 / 6.0), 1e-12);
    EXPECT_NEAR(error->relativeRmse, std::sqrt(1.0 / 6.0), 1e-12);
    // Luminances 1.2126 and 1 against 1 and 1.
    EXPECT_NEAR(error->meanRatio, (1.2126 + 1.0) / 2.0, 1e-6);

    // Relative RMSE divides by the mean of all reference values, not per channel.
    Image dim = filled(1, 1, {0.0f, 0.5f, 1.0f});
    Image off = filled(1, 1, {0.3f, 0.5f, 1.0f});
    auto relative = compareImages(off, dim);
    ASSERT_TRUE(relative);
    EXPECT_NEAR(relative->rmse, 0.3 / std::sqrt(3.0), 1e-7);
    EXPECT_NEAR(relative->relativeRmse, (0.3 / std::sqrt(3.0)) / 0.5, 1e-7);
    EXPECT_NEAR(relative->meanRatio,
                (0.2126 * 0.3 + 0.7152 * 0.5 + 0.0722) / (0.7152 * 0.5 + 0.0722), 1e-6);

    auto same = compareImages(reference, reference);
    ASSERT_TRUE(same);
    EXPECT_EQ(same->rmse, 0.0);
    EXPECT_EQ(same->meanRatio, 1.0);
    // Channel ratios: 2 + 1 against 1 + 1 in red, equal in green and blue.
    EXPECT_NEAR(error->channelRatio.r, 1.5, 1e-12);
    EXPECT_NEAR(error->channelRatio.g, 1.0, 1e-12);
    EXPECT_NEAR(error->channelRatio.b, 1.0, 1e-12);
}

TEST(BlotchIndex, CountsDisagreementBetweenBlocksNotScaleNorNoiseWithinThem) {
    // 8 × 4 pixels: two 4 × 4 blocks. Twice the reference everywhere is a scale: index 0.
    Image reference = filled(8, 4, glm::vec3(1.0f));
    Image twice = filled(8, 4, glm::vec3(2.0f));
    auto scaled = blotchIndex(twice, reference);
    ASSERT_TRUE(scaled) << scaled.error().message;
    EXPECT_NEAR(*scaled, 0.0, 1e-7);
    // Noise that averages out within each block: index 0.
    Image noisy = reference;
    for (uint32_t y = 0; y < 4; ++y)
        for (uint32_t x = 0; x < 8; ++x) noisy.at(x, y) = glm::vec3((x + y) % 2 ? 1.5f : 0.5f);
    auto withinBlocks = blotchIndex(noisy, reference);
    ASSERT_TRUE(withinBlocks);
    EXPECT_NEAR(*withinBlocks, 0.0, 1e-7);
    // One block at 1.5, the other at 0.5: mean-matched already, each block off by 0.5.
    Image blotchy = reference;
    for (uint32_t y = 0; y < 4; ++y)
        for (uint32_t x = 0; x < 8; ++x) blotchy.at(x, y) = glm::vec3(x < 4 ? 1.5f : 0.5f);
    auto blotches = blotchIndex(blotchy, reference);
    ASSERT_TRUE(blotches);
    EXPECT_NEAR(*blotches, 0.5, 1e-6);
    EXPECT_FALSE(blotchIndex(Image(8, 4), reference));  // black: nothing to scale
}

TEST(CompareImages, RejectsMismatchedBlackAndNonFiniteImages) {
    auto size = compareImages(Image(2, 2), Image(2, 3));
    ASSERT_FALSE(size);
    EXPECT_NE(size.error().message.find("2x2 but the reference is 2x3"), std::string::npos);
    auto black = compareImages(filled(2, 2, glm::vec3(1.0f)), Image(2, 2));
    ASSERT_FALSE(black);
    EXPECT_NE(black.error().message.find("reference mean is 0"), std::string::npos)
        << black.error().message;
    Image nan = filled(2, 2, glm::vec3(1.0f));
    nan.at(1, 0).y = std::numeric_limits<float>::quiet_NaN();
    auto nanError = compareImages(nan, filled(2, 2, glm::vec3(1.0f)));
    ASSERT_FALSE(nanError);
    EXPECT_NE(nanError.error().message.find("pixel (1, 0)"), std::string::npos);
}

TEST(BlockAverage, AveragesWholeAndEdgeBlocks) {
    // 5 × 3 with pixel (x, y) = (x, y, x + 10y): 2 × 2 blocks give 3 × 2, the edge blocks
    // averaging the pixels they hold.
    Image image(5, 3);
    for (uint32_t y = 0; y < 3; ++y)
        for (uint32_t x = 0; x < 5; ++x) image.at(x, y) = glm::vec3(x, y, x + 10.0f * y);
    auto averaged = blockAverage(image, 2);
    ASSERT_TRUE(averaged) << averaged.error().message;
    ASSERT_EQ(averaged->width, 3u);
    ASSERT_EQ(averaged->height, 2u);
    EXPECT_EQ(averaged->at(0, 0), glm::vec3(0.5f, 0.5f, 5.5f));
    EXPECT_EQ(averaged->at(2, 0), glm::vec3(4.0f, 0.5f, 9.0f));   // one column of two rows
    EXPECT_EQ(averaged->at(1, 1), glm::vec3(2.5f, 2.0f, 22.5f));  // two columns of one row
    EXPECT_EQ(averaged->at(2, 1), glm::vec3(4.0f, 2.0f, 24.0f));  // the corner pixel alone
    // Block 1 is the image itself; the error of averages falls where the error is fine detail.
    auto same = blockAverage(image, 1);
    ASSERT_TRUE(same);
    EXPECT_EQ(same->pixels, image.pixels);
    Image checker(8, 8), grey(8, 8);
    for (uint32_t y = 0; y < 8; ++y)
        for (uint32_t x = 0; x < 8; ++x) {
            checker.at(x, y) = glm::vec3(float((x + y) % 2));
            grey.at(x, y) = glm::vec3(0.5f);
        }
    EXPECT_NEAR(compareImages(checker, grey)->relativeRmse, 1.0, 1e-9);
    EXPECT_NEAR(compareImages(*blockAverage(checker, 2), *blockAverage(grey, 2))->relativeRmse, 0.0,
                1e-9);
    EXPECT_FALSE(blockAverage(image, 0));
    EXPECT_FALSE(blockAverage(Image(), 4));
}

}  // namespace
}  // namespace pic
