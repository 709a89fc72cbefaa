// GoogleTest main shared by every hairrig test executable.
//
// ctest only sees an exit code, so a test executable whose tests were skipped
// (hardware absent, ../shared absent) exits 77, which hairrig_add_test maps to
// ctest's "Skipped" (SKIP_RETURN_CODE). Keep tests that share a skip condition
// in their own executable so that a skip never hides a pass.
#include <gtest/gtest.h>

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  const int failed = RUN_ALL_TESTS();
  if (failed != 0) return failed;
  const auto* unit = ::testing::UnitTest::GetInstance();
  if (unit->skipped_test_count() > 0) return 77;
  return 0;
}
