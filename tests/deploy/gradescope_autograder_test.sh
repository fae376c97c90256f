#!/usr/bin/env bash
# Deploy.gradescope_autograder (issue #34): the archive deploy/gradescope/make-autograder.sh makes
# for jobs/grade/dandelion, run the way Gradescope runs it. A fresh Debian 12 (mmdebstrap chroot)
# gets the archive unpacked in /autograder/source and run_autograder copied to
# /autograder/run_autograder; setup.sh installs the farm from the .deb inside; then
# run_autograder grades three submissions from /autograder (nothing handed in, the references
# themselves, and a half-wrong one) and each /autograder/results/results.json is checked against
# Gradescope's documented keys (tests/data/gradescope/results.schema.json) and the expected
# scores. Grading must render nothing: the shipped references stay byte for byte and no other
# scene appears beside them. setup.sh must refuse a system it does not support (Ubuntu 22.04).
#
# With FARM_GRADESCOPE_SYSTEM=ubuntu (what Deploy.gradescope_ubuntu sets) the chroot is a fresh
# Ubuntu 24.04 instead, Gradescope's own base image: setup.sh builds farm there from the source
# the archive carries (minutes), and the farm it built must render the references the Debian
# .deb rendered bit for bit (farm compare --metric exact), under the same scene hashes.
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
system="${FARM_GRADESCOPE_SYSTEM:-debian}"
case "$system" in debian | ubuntu) ;; *) fail "FARM_GRADESCOPE_SYSTEM=$system: debian or ubuntu" ;; esac
require_root "unpacking the autograder into a chroot"
require_tool mmdebstrap
require_tool cpack
require_tool dpkg-deb
require_tool zip
require_tool unzip
require_tool python3
require_tool git
# The rubric's cow is the lab's model in shared/ beside the checkout.
[ -f "$FARM_SOURCE_DIR/../shared/assets/dae/cow.dae" ] || skip "the dandelion rubric's cow ($FARM_SOURCE_DIR/../shared/assets/dae/cow.dae) is missing"

work=$(mktemp -d /tmp/farm-gradescope-test.XXXXXX)
root="$work/root"
cleanup() {
  chroot_cleanup
  rm -rf "$work"
}
trap cleanup EXIT
started=$SECONDS
elapsed() { echo "$((SECONDS - started)) s"; }

# The rubric as a lab lays it out: main/ (the checkout: the rubric, its jobs' assets) beside
# shared/ (the cow). Copied, links resolved, so that neither this checkout's folder name nor a
# shared/ that is a link (which the farm's confinement rightly refuses) changes what is packed.
lab="$work/lab"
mkdir -p "$lab/main/jobs/grade" "$lab/shared/assets/dae"
cp -rL "$FARM_SOURCE_DIR/jobs/grade/dandelion" "$lab/main/jobs/grade/"
cp -rL "$FARM_SOURCE_DIR/jobs/assets" "$lab/main/jobs/"
cp -L "$FARM_SOURCE_DIR/../shared/assets/dae/cow.dae" "$lab/shared/assets/dae/"
rubric="$lab/main/jobs/grade/dandelion/rubric.json"

deb=$(farm_deb)
zip_file="$work/autograder.zip"
"$FARM_SOURCE_DIR/deploy/gradescope/make-autograder.sh" "$rubric" "$zip_file" --deb "$deb" --source "$FARM_SOURCE_DIR"
echo "archive made after $(elapsed)"

# What Gradescope requires of the zip: both scripts at its root, run_autograder executable; and
# what this one promises: relative entries only, the .deb, a reference pair per scene.
entries=$(unzip -Z1 "$zip_file")
for entry in setup.sh run_autograder "$(basename "$deb")" farm-source.tar.gz grading/references.sha256 \
  lab/main/jobs/grade/dandelion/rubric.json lab/shared/assets/dae/cow.dae lab/main/jobs/assets/cornell_box.mtl; do
  grep -qxF "$entry" <<<"$entries" || fail "the archive holds no $entry"
done
! grep -qE '^/|(^|/)\.\.(/|$)' <<<"$entries" || fail "an archive entry is absolute or climbs out: $entries"
unzip -Z "$zip_file" run_autograder | grep -q '^-rwx' || fail "run_autograder is not executable in the archive"
references=$(grep -cE '^grading/references/[0-9a-f]{64}/reference\.(exr|png)$' <<<"$entries")
[ "$references" -eq 6 ] || fail "expected 3 scenes' reference.exr and .png in the archive, found $references files"

# A fresh Ubuntu 24.04 root filesystem (mmdebstrap's apt variant, main and universe, with the
# updates), made once per build folder like common.sh's Debian one. Debian 12 has no package of
# Ubuntu's archive key, so the bootstrap trusts the archive unchecked; the tree it makes then
# checks every later download (setup.sh's apt) against the ubuntu-keyring it installed.
ubuntu_rootfs_tar() {
  local tar="$deploy_cache/noble.tar" mirror=http://archive.ubuntu.com/ubuntu
  (
    flock 9
    if [ ! -s "$tar" ]; then
      mmdebstrap --variant=apt --format=tar --quiet --skip=cleanup/apt/lists --components=main,universe \
        --customize-hook='printf "deb [signed-by=/usr/share/keyrings/ubuntu-archive-keyring.gpg] %s %s main universe\n" \
          '"$mirror"' noble '"$mirror"' noble-updates '"$mirror"' noble-security >"$1/etc/apt/sources.list"' \
        noble "$tar.part" "deb [trusted=yes] $mirror noble main universe" \
        "deb [trusted=yes] $mirror noble-updates main universe" "deb [trusted=yes] $mirror noble-security main universe" >&2 \
        && mv "$tar.part" "$tar"
    fi
  ) 9>"$deploy_cache/rootfs.lock"
  [ -s "$tar" ] || fail "mmdebstrap could not make an Ubuntu 24.04 root filesystem from $mirror"
  echo "$tar"
}

# The layout Gradescope builds (its Autograder Specifications): the zip in /autograder/source,
# run_autograder copied to /autograder/, the submission and the results folders.
if [ "$system" = ubuntu ]; then
  tar=$(ubuntu_rootfs_tar)
  chroot_from_tar "$root" "$tar"
  grep -qx 'VERSION_ID="24.04"' "$root/etc/os-release" || fail "the Ubuntu chroot is not 24.04: $(cat "$root/etc/os-release")"
  farm_path=/usr/local/bin/farm
else
  chroot_fresh "$root"
  farm_path=/usr/bin/farm
fi
in_chroot "$root" bash -c '! command -v farm && test ! -e /usr/local/bin/farm' >/dev/null \
  || fail "the fresh chroot already has a farm"
mkdir -p "$root/autograder/source" "$root/autograder/submission" "$root/autograder/results"
unzip -q "$zip_file" -d "$root/autograder/source"
cp "$root/autograder/source/run_autograder" "$root/autograder/run_autograder"

# A system setup.sh does not support: it stops before installing anything, naming the two it does
# (Gradescope's default base image, Ubuntu 22.04, here).
os_release=$(readlink -f "$root/etc/os-release")
[[ "$os_release" == "$root"/* ]] || fail "the chroot's /etc/os-release leads outside it ($os_release)"
cp "$os_release" "$work/os-release"
printf 'ID=ubuntu\nVERSION_ID="22.04"\nPRETTY_NAME="Ubuntu 22.04.5 LTS"\n' >"$os_release"
if in_chroot "$root" bash /autograder/source/setup.sh >"$work/refused.log" 2>&1; then
  cp "$work/os-release" "$os_release"
  fail "setup.sh accepted Ubuntu 22.04: $(cat "$work/refused.log")"
fi
cp "$work/os-release" "$os_release"
grep -q 'Ubuntu 24.04' "$work/refused.log" && grep -q 'Debian 12' "$work/refused.log" \
  || fail "setup.sh's refusal of Ubuntu 22.04 does not name what it supports: $(cat "$work/refused.log")"
in_chroot "$root" bash -c '! command -v farm && test ! -e /usr/local/bin/farm' >/dev/null \
  || fail "setup.sh installed a farm on a system it refused"
echo "setup.sh refused Ubuntu 22.04: $(tail -1 "$work/refused.log")"

setup_started=$SECONDS
in_chroot "$root" bash /autograder/source/setup.sh >"$work/setup.log" 2>&1 \
  || { tail -40 "$work/setup.log"; fail "setup.sh failed in the $system chroot"; }
grep '^setup.sh: ' "$work/setup.log"
echo "setup.sh done in $((SECONDS - setup_started)) s, after $(elapsed)"
# The farm where setup.sh says, the .deb's version; on Ubuntu built here, not from any package.
[ "$(in_chroot "$root" "$farm_path" --version)" = "farm $(dpkg-deb -f "$deb" Version)" ] \
  || fail "$farm_path in the chroot is not the .deb's version"
if [ "$system" = ubuntu ]; then
  ! in_chroot "$root" dpkg -S "$farm_path" >/dev/null 2>&1 || fail "$farm_path came from a package"
  ! in_chroot "$root" test -e /usr/bin/farm || fail "a farm in /usr/bin on Ubuntu: the .deb was installed"
fi

grading="$root/autograder/source/grading"
snapshot() {  # every reference picture with its checksum and modification time
  (cd "$grading/references" && find . -type f \( -name reference.exr -o -name reference.png \) \
    -printf '%p %T@ ' -exec sha256sum {} \; | sort)
}
before=$(snapshot)

# run_autograder as Gradescope starts it: from /autograder, on the submission now in place.
grade() {
  rm -rf "$root/autograder/submission" "$root/autograder/results/results.json"
  mkdir -p "$root/autograder/submission"
  "$@"
  in_chroot "$root" bash -c 'cd /autograder && ./run_autograder' >"$work/run.log" 2>&1 \
    || { cat "$work/run.log"; fail "run_autograder failed"; }
  cat "$work/run.log"
  ! grep -q "was rendered here" "$work/run.log" || fail "run_autograder rendered a reference"
  [ -s "$root/autograder/results/results.json" ] || fail "run_autograder wrote no results.json"
}

# Checks results.json against the schema of Gradescope's keys, and each test's score:
# EXPECT is task=score (exact), task<score (less), or task=missing (0, the file reported missing).
check_results() {
  local schema="$FARM_SOURCE_DIR/tests/data/gradescope/results.schema.json"
  local results="$root/autograder/results/results.json" by_hand=1
  # The project's validator (jsonschema from the test venv, as farm_grade_test uses it); Debian's
  # jsonschema 4.10 cannot resolve this schema's relative $id, so without the venv the keys are
  # checked by hand below.
  if [ -x "${FARM_TEST_PYTHON:-}" ] && "$FARM_TEST_PYTHON" -c 'import jsonschema' 2>/dev/null; then
    "$FARM_TEST_PYTHON" "$FARM_SOURCE_DIR/tests/python/validate_json_schema.py" "$schema" "$results" || return 1
    by_hand=0
  fi
  KEYS_BY_HAND=$by_hand python3 - "$schema" "$results" "$@" <<'EOF'
import json, os, sys
schema_file, results_file, *expect = sys.argv[1:]
schema = json.load(open(schema_file))
results = json.load(open(results_file))
if os.environ["KEYS_BY_HAND"] == "1":  # the schema's keys and its one requirement
    unknown = set(results) - set(schema["properties"])
    assert not unknown, f"keys Gradescope does not document: {unknown}"
    test_keys = set(schema["$defs"]["test"]["properties"])
    for t in results.get("tests", []):
        assert not set(t) - test_keys, f"test keys Gradescope does not document: {set(t) - test_keys}"
    assert "score" in results, "no top-level score"
tests = {t["name"]: t for t in results["tests"]}
maximum = {"cow-raster": 40, "whitted-shadows-mirror": 30, "cornell-path": 30}
assert set(tests) == set(maximum), f"tests {sorted(tests)}, expected {sorted(maximum)}"
for name, t in tests.items():
    assert t["max_score"] == maximum[name], f"{name}: max_score {t['max_score']}"
    assert t["status"] == ("passed" if t["score"] >= t["max_score"] else "failed"), f"{name}: status {t['status']}"
for rule in expect:
    if "<" in rule:
        name, bound = rule.split("<")
        assert tests[name]["score"] < float(bound), f"{name}: {tests[name]['score']}, expected < {bound}"
    else:
        name, value = rule.split("=")
        if value == "missing":
            assert tests[name]["score"] == 0 and "missing" in tests[name]["output"], f"{name}: {tests[name]}"
        else:
            assert tests[name]["score"] == float(value), f"{name}: {tests[name]['score']}, expected {value}"
total = sum(t["score"] for t in tests.values())
assert abs(results["score"] - total) < 1e-6, f"score {results['score']}, tests add up to {total}"
print(f"results.json valid; score {results['score']}: " + ", ".join(f"{n} {t['score']}" for n, t in tests.items()))
EOF
}

# 1. Nothing handed in: every task 0, each saying its file is missing.
grade true
check_results cow-raster=missing whitted-shadows-mirror=missing cornell-path=missing \
  || fail "an empty submission's results.json"

# farm grade laid out each scene's job in references/<hash>/job/<job file>: which picture is whose.
reference_png() {
  local job="$1" folder
  folder=$(dirname "$(dirname "$(ls "$grading"/references/*/job/"$job")")")
  echo "$folder/reference.png"
}
cow=$(reference_png cow.json) whitted=$(reference_png whitted.json) cornell=$(reference_png cornell.json)

# 2. The references themselves, handed in: full marks.
grade eval 'cp "$cow" "$root/autograder/submission/cow.png"; cp "$whitted" "$root/autograder/submission/whitted.png";
  cp "$cornell" "$root/autograder/submission/cornell.png"'
check_results cow-raster=40 whitted-shadows-mirror=30 cornell-path=30 || fail "a correct submission's results.json"

# 3. The cow right, the cow again for the Whitted scene, no Cornell box: 40 and less than 30.
grade eval 'cp "$cow" "$root/autograder/submission/cow.png"; cp "$cow" "$root/autograder/submission/whitted.png"'
check_results cow-raster=40 "whitted-shadows-mirror<30" cornell-path=missing || fail "a half-wrong submission's results.json"

# Nothing rendered: the shipped references untouched (content and time), and no other scene.
after=$(snapshot)
[ "$before" = "$after" ] || fail "grading changed or added references:
before: $before
after:  $after"
[ "$(ls "$grading/references" | sort)" = "$(unzip -Z1 "$zip_file" | sed -n 's|^grading/references/\([0-9a-f]*\)/reference\.exr$|\1|p' | sort)" ] \
  || fail "grading made a reference folder the archive did not carry: $(ls "$grading/references")"

if [ "$system" = ubuntu ]; then
  # The farm built on Ubuntu renders the rubric's scenes as the Debian .deb's farm did: an empty
  # class graded into a fresh folder renders every reference, under the same scene hashes, and
  # each must equal the shipped one in every pixel and channel.
  in_chroot "$root" bash -c 'mkdir -p /tmp/empty && /usr/local/bin/farm grade /autograder/source/lab/main/jobs/grade/dandelion/rubric.json /tmp/empty --out /tmp/rerendered' \
    >"$work/rerender.log" 2>&1 || { cat "$work/rerender.log"; fail "the Ubuntu farm could not render the references"; }
  rerendered="$root/tmp/rerendered/references"
  [ "$(ls "$rerendered" | sort)" = "$(ls "$grading/references" | sort)" ] \
    || fail "the Ubuntu farm's scene hashes differ from the Debian farm's: $(ls "$rerendered") vs $(ls "$grading/references")"
  for reference in "$grading"/references/*/; do
    reference="${reference%/}"
    hash=$(basename "$reference")
    "$FARM_BINARY" compare "$reference/reference.exr" "$rerendered/$hash/reference.exr" --metric exact >"$work/compare.log" 2>&1 \
      || { cat "$work/compare.log"; fail "scene $hash ($(ls "$reference/job" | grep '\.json$' | head -1)): the Ubuntu farm's render differs from the Debian reference"; }
  done
  echo "the Ubuntu-built farm rendered the $(ls "$rerendered" | wc -l) references bit for bit"
fi
echo "PASS: the autograder archive installed and graded three submissions in a fresh $system chroot, rendering nothing ($(elapsed))"
