// EXR write/read round trip and atomic output.
#include "qsil/error.h"
#include "qsil/image.h"

#include <gtest/gtest.h>

#include <filesystem>

namespace qsil {

TEST(ImageIO, ExrRoundTripKeepsChannelsValuesAndAttributes) {
  Image img;
  img.width = 7;
  img.height = 5;
  img.channel_names = {"R", "G", "B", "dtheta0.R"};
  for (size_t c = 0; c < img.channel_names.size(); ++c) {
    img.planes.emplace_back(size_t(img.width) * img.height);
    for (int i = 0; i < img.width * img.height; ++i) img.planes[c][i] = float(c * 100 + i) * 0.25f - 3.0f;
  }
  img.attributes["qsil:param0"] = "spot:translate:0,1,0";
  const auto path = std::filesystem::temp_directory_path() / "qsil_roundtrip_test.exr";
  write_exr(path, img);
  const Image back = read_exr(path);
  ASSERT_EQ(back.width, img.width);
  ASSERT_EQ(back.height, img.height);
  for (size_t c = 0; c < img.channel_names.size(); ++c) {
    const int bc = back.channel_index(img.channel_names[c]);
    ASSERT_GE(bc, 0) << img.channel_names[c];
    for (int y = 0; y < img.height; ++y)
      for (int x = 0; x < img.width; ++x) EXPECT_EQ(back.at(bc, x, y), img.at(int(c), x, y));  // float: exact
  }
  EXPECT_EQ(back.attributes.at("qsil:param0"), "spot:translate:0,1,0");
  // No temporary file is left beside the output.
  for (const auto& e : std::filesystem::directory_iterator(path.parent_path()))
    EXPECT_EQ(e.path().string().find("qsil_roundtrip_test.exr.tmp"), std::string::npos);
  std::filesystem::remove(path);
}

TEST(ImageIO, ReadingAMissingOrBrokenFileIsAOneLineError) {
  EXPECT_THROW(read_exr("/nonexistent/x.exr"), Error);
  const auto path = std::filesystem::temp_directory_path() / "qsil_broken_test.exr";
  {
    std::FILE* f = std::fopen(path.c_str(), "w");
    std::fputs("not an exr", f);
    std::fclose(f);
  }
  try {
    read_exr(path);
    FAIL() << "no error";
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find(path.string()), std::string::npos);
    EXPECT_EQ(m.find('\n'), std::string::npos);
  }
  std::filesystem::remove(path);
}

TEST(ImageIO, WritingIntoAMissingDirectoryFailsWithoutLeavingAFile) {
  Image img;
  img.width = img.height = 2;
  img.channel_names = {"R"};
  img.planes = {std::vector<float>(4, 1.0f)};
  EXPECT_THROW(write_exr("/nonexistent_dir_qsil/out.exr", img), Error);
  EXPECT_FALSE(std::filesystem::exists("/nonexistent_dir_qsil/out.exr"));
}

}  // namespace qsil
