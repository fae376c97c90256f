#!/usr/bin/env bash
# Deploy.gradescope_ubuntu (issue #34): Deploy.gradescope_autograder on Gradescope's own base
# image, Ubuntu 24.04, instead of Debian 12: a fresh noble chroot from archive.ubuntu.com, where
# setup.sh installs the build packages and compiles farm from the archive's farm-source.tar.gz;
# then the same three submissions are graded, and the farm built there must render the Debian
# references bit for bit. It downloads ~150 MB of packages and compiles farm from nothing
# (setup.sh took 165 s on 2 cores: 37 s of apt, 128 s of build; 3 to 5 minutes in all, plus
# 45 s to bootstrap Ubuntu the first time), so it runs only when asked:
# FARM_DEPLOY_UBUNTU=1 ctest -R Deploy.gradescope_ubuntu
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
[ "${FARM_DEPLOY_UBUNTU:-0}" = 1 ] \
  || skip "building farm on a fresh Ubuntu 24.04 takes minutes: run with FARM_DEPLOY_UBUNTU=1"
FARM_GRADESCOPE_SYSTEM=ubuntu exec bash "$(dirname "$0")/gradescope_autograder_test.sh"
