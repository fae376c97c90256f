#!/usr/bin/env bash
# Gradescope autograder set-up (a sample): Gradescope runs this once, as root, when it builds the
# autograder image, with this folder's contents in /autograder/source. Point the autograder at a
# Debian 12 base image (Gradescope allows custom images), since deploy/install-deps.sh installs
# Debian 12's packages. The farm's checkout is expected at /autograder/source/renderfarm, the
# lab's shared assets at /autograder/source/shared.
set -euo pipefail
cd /autograder/source/renderfarm
deploy/install-deps.sh
cmake --preset release
cmake --build --preset release --target farm
# Render the references once now, so grading a submission renders nothing.
mkdir -p /autograder/source/empty
./build/release/server/farm grade jobs/grade/dandelion/rubric.json /autograder/source/empty \
    --out /autograder/source/grading
