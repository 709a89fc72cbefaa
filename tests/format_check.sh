#!/usr/bin/env bash
# ctest tests/format: every C++ file of the repository is as clang-format
# (.clang-format) leaves it. Skipped (77) without clang-format 14, the
# version Debian 12 ships (other versions format some constructs otherwise).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
if ! command -v clang-format >/dev/null 2>&1; then
  echo "SKIPPED: clang-format is absent (apt-get install clang-format)"
  exit 77
fi
version=$(clang-format --version | sed -n 's/.*version \([0-9]*\)\..*/\1/p')
if [ "$version" != "14" ]; then
  echo "SKIPPED: clang-format $version; the tree is formatted with Debian 12's clang-format 14"
  exit 77
fi
files=$(git ls-files '*.cpp' '*.h' 2>/dev/null || find . -path ./build\* -prune -o \( -name '*.cpp' -o -name '*.h' \) -print)
if ! clang-format --dry-run --Werror $files 2>/tmp/hairrig-format-$$.txt; then
  grep -m 20 'error:' /tmp/hairrig-format-$$.txt
  echo "Run: clang-format -i \$(git ls-files '*.cpp' '*.h')"
  rm -f /tmp/hairrig-format-$$.txt
  exit 1
fi
rm -f /tmp/hairrig-format-$$.txt
echo "$(echo "$files" | wc -w) files formatted"
