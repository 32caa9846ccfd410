#!/usr/bin/env bash
# three_tests.sh - each test_NAME is one ctest case web.three.NAME (tests/web/CMakeLists.txt). The
# helpers (skip, need_node, need_chromium, node_test) are web_tests.sh's.
source "$(dirname "$0")/web_common.sh"

# (test_* functions go above this line)
run_test "$1"
