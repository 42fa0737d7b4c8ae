// Invariant checks (qsil/check.h): QSIL_CHECK aborts with file:line and the condition;
// QSIL_DCHECK does the same when the build defines QSIL_DCHECKS and otherwise does not evaluate
// its condition at all; the library's own checks fire on invariant violations (a film layout for
// more than 8 parameters).
#include "qsil/check.h"
#include "qsil/film.h"

#include <gtest/gtest.h>

namespace qsil {
namespace {

TEST(CheckDeathTest, CheckAbortsWithFileLineAndCondition) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  const int answer = 41;
  EXPECT_DEATH(QSIL_CHECK(answer == 42), "check_test.cpp:[0-9]+: check failed: answer == 42");
  EXPECT_DEATH(QSIL_CHECK_MSG(answer > 50, "answer " << answer), "check failed: answer > 50 \\(answer 41\\)");
}

TEST(CheckDeathTest, CheckPassesSilently) {
  int evaluated = 0;
  QSIL_CHECK(++evaluated == 1);
  EXPECT_EQ(evaluated, 1);
}

TEST(CheckDeathTest, DcheckFollowsTheBuildOption) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  int evaluated = 0;
  QSIL_DCHECK(++evaluated > 0);
#ifdef QSIL_DCHECKS
  EXPECT_EQ(evaluated, 1);
  EXPECT_DEATH(QSIL_DCHECK(evaluated == 0), "check failed: evaluated == 0");
#else
  EXPECT_EQ(evaluated, 0);  // not evaluated: free in release builds
#endif
}

TEST(CheckDeathTest, LibraryInvariants) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_DEATH(FilmLayout(9), "check failed");
  EXPECT_DEATH(Film(0, 4, FilmLayout(1)), "check failed");
}

}  // namespace
}  // namespace qsil
