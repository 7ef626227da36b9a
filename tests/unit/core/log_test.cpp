#include "runtime/core/log.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <fcntl.h>
#include <fstream>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include "tests/test_tmp.h"

namespace kaskad {
namespace {

// Lines logged from several threads at once come out whole, one per line: each is written with
// one call (stdio locks the stream per call), not as prefix, message and newline apart.
TEST(Log, LinesFromThreadsDoNotInterleave) {
  const std::string path = (testing_util::test_tmp() / "stderr.txt").string();
  std::fflush(stderr);
  const int saved = dup(fileno(stderr));
  const int file = open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  ASSERT_GE(saved, 0);
  ASSERT_GE(file, 0);
  dup2(file, fileno(stderr));
  close(file);
  constexpr int kThreads = 8, kLines = 2000;
  {
    std::vector<std::jthread> threads;
    for (int t = 0; t < kThreads; ++t)
      threads.emplace_back([t] {
        for (int i = 0; i < kLines; ++i) log::info("thread %d line %d of a message", t, i);
      });
  }
  std::fflush(stderr);
  dup2(saved, fileno(stderr));
  close(saved);

  std::ifstream in(path);
  const std::regex whole(R"(\[kaskad info\] thread \d line \d+ of a message)");
  int lines = 0, broken = 0;
  for (std::string line; std::getline(in, line); ++lines)
    if (!std::regex_match(line, whole) && ++broken <= 3) ADD_FAILURE() << "interleaved: " << line;
  EXPECT_EQ(lines, kThreads * kLines);
  EXPECT_EQ(broken, 0);
}

}  // namespace
}  // namespace kaskad
