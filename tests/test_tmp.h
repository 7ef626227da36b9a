// The running test's own scratch folder. CTest runs every test in a process of its own, two at a
// time (`-j 2`), so a file name that two tests share is a race: one test renders the scene the
// other has just written (ToneMappingTest read ColourFollowsTheCurve...'s card that way). Tests
// write their files here, never straight into KASKAD_TEST_TMP.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace kaskad::testing_util {

/// KASKAD_TEST_TMP/<suite>.<test>/`sub`, created. Parameterised names have '/' replaced by '_';
/// outside a test (a suite's set-up) the folder is named after the suite alone.
inline std::filesystem::path test_tmp(const std::string& sub = {}) {
  const ::testing::UnitTest& unit = *::testing::UnitTest::GetInstance();
  std::string name = "no_test";
  if (const ::testing::TestInfo* info = unit.current_test_info())
    name = std::string(info->test_suite_name()) + "." + info->name();
  else if (const ::testing::TestSuite* suite = unit.current_test_suite())
    name = suite->name();
  for (char& c : name)
    if (c == '/') c = '_';
  std::filesystem::path dir = std::filesystem::path(KASKAD_TEST_TMP) / name;
  if (!sub.empty()) dir /= sub;
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace kaskad::testing_util
