#!/usr/bin/env bash
# Deploy.gradescope_ubuntu (issue #34): Deploy.gradescope_autograder on Gradescope's own base
# image, Ubuntu 24.04, instead of Debian 12: a fresh noble chroot from archive.ubuntu.com, where
# setup.sh installs the build packages and compiles farm from the archive's farm-source.tar.gz;
# then the same three submissions are graded, and the farm built there must render the Debian
# references bit for bit. It compiles farm from nothing (about 6 minutes on 2 cores, plus
# 1.5 minutes of apt), so it runs only when asked:
# FARM_DEPLOY_UBUNTU=1 ctest -R Deploy.gradescope_ubuntu
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
[ "${FARM_DEPLOY_UBUNTU:-0}" = 1 ] \
  || skip "building farm on a fresh Ubuntu 24.04 takes ~8 minutes: run with FARM_DEPLOY_UBUNTU=1"
FARM_GRADESCOPE_SYSTEM=ubuntu exec bash "$(dirname "$0")/gradescope_autograder_test.sh"
