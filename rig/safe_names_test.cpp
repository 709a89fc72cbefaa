#include "rig/safe_names.h"

#include <gtest/gtest.h>

#include <vector>

namespace hairrig {
namespace {

TEST(SafeNames, SubjectNamesBecomeFolderNamesOrAreRefused) {
  EXPECT_EQ(*SubjectFolderName("wig_03"), "wig_03");
  EXPECT_EQ(*SubjectFolderName("Wig 03 long.v2"), "Wig_03_long.v2");
  for (const std::string& bad : std::vector<std::string>{
           "", "../x", "..", ".hidden", "/etc/passwd", "a/b", "a\\b", std::string("a\nb"),
           std::string("tab\there"), std::string(101, 'a'), "semi;colon", "star*"}) {
    auto r = SubjectFolderName(bad);
    EXPECT_FALSE(r.ok()) << "accepted '" << bad << "' as " << (r.ok() ? *r : "");
  }
  auto r = SubjectFolderName("../x");
  EXPECT_NE(r.status().message().find("separator"), std::string::npos) << r.status().ToString();
  r = SubjectFolderName(std::string("a\x01"));
  EXPECT_NE(r.status().message().find("\\x01"), std::string::npos)
      << "control characters are shown escaped";
}

TEST(SafeNames, DeviceTextBecomesAFileNamePart) {
  EXPECT_EQ(FileNamePart("SIM-CAM-UPPER"), "SIM-CAM-UPPER");
  EXPECT_EQ(FileNamePart("../../etc"), "_._.._etc");  // no separator survives
  EXPECT_EQ(FileNamePart("Canon EOS/5D"), "Canon_EOS_5D");
  EXPECT_EQ(FileNamePart(""), "_");
  EXPECT_EQ(FileNamePart(".x"), "_x");
}

}  // namespace
}  // namespace hairrig
