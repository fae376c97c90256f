#!/usr/bin/env bash
# Builds the zip Gradescope asks for to grade a rubric of `farm grade` (jobs/grade/README.md):
# setup.sh and run_autograder at its root, the farm's .deb and its source (for an Ubuntu 24.04
# image, which builds it), the rubric with its jobs and their assets, and the references already
# rendered, so that grading a submission on Gradescope only compares images. Run it on the
# Debian 12 machine that built the farm. See --help.
set -euo pipefail

usage() {
  cat <<'EOF'
Usage: deploy/gradescope/make-autograder.sh RUBRIC OUT.zip [--deb PATH] [--source DIR]

Builds a Gradescope autograder archive for a `farm grade` rubric (jobs/grade/README.md):

  setup.sh          Gradescope runs it once, as root, when it builds the autograder image:
                    installs the farm and checks the references' checksums. On Debian 12 it
                    installs the .deb below (apt-get install ./renderfarm_*.deb); on Ubuntu
                    24.04 it installs the build packages (deploy/install-deps.sh --build) and
                    builds farm from farm-source.tar.gz into /usr/local/bin (minutes); on any
                    other system it stops, naming these two.
  run_autograder    Gradescope runs it for each submission: `farm grade RUBRIC --gradescope`
                    grades /autograder/submission and writes /autograder/results/results.json.
  renderfarm_*.deb  the farm, as `cpack -G DEB` makes it from the build folder.
  farm-source.tar.gz
                    the source the .deb was built from: the files of the checkout that git
                    tracks or would track (git ls-files --cached --others --exclude-standard).
  lab/...           the rubric, its jobs and every file their models read (textures, .mtl ...),
                    at the same paths relative to each other as here.
  grading/references/<scene hash>/reference.{exr,png}
                    the references, rendered now by the .deb's own farm; farm grade finds them
                    by scene hash and renders nothing on Gradescope.
  grading/references.sha256

Every file must lie inside the rubric's folder, or inside its asset_root when that folder holds
the rubric's folder (jobs/grade/dandelion's asset_root holds the checkout and ../shared): a job or
model elsewhere is refused, naming the file. The archive holds relative paths only, and copies of
files, not links.

Options:
  --deb PATH    the farm's .deb (default: made now with `cpack -G DEB` in the build folder,
                $FARM_BUILD_DIR or build/release beside this script's checkout)
  --source DIR  the git checkout the .deb was built from (default: the one holding this
                script); its project version must be the .deb's
  -h, --help    this text

On Gradescope, choose the Base Image OS Ubuntu, Version 24.04: it has most of the library
versions Debian 12 builds the farm with (OpenEXR 3.1, gRPC 1.51, protobuf 3.21, fmt 9; Embree 4
and tinygltf 2.8 where Debian has 3 and 2.7). The default, Ubuntu 22.04, has older ones (OpenEXR
2.5, gRPC 1.30) and setup.sh refuses it. The references are rendered by the .deb's farm; a farm
built on Ubuntu 24.04 renders the same pictures bit for bit and computes the same scene hashes
(tests/deploy/gradescope_ubuntu_test.sh checks both).

Needs: python3, zip, unzip, dpkg-deb, sha256sum, git, tar, gzip (and cpack without --deb).
EOF
}

die() {
  echo "make-autograder.sh: $*" >&2
  exit 2
}

rubric="" out="" deb="" source=""
while [ $# -gt 0 ]; do
  case "$1" in
    -h | --help) usage; exit 0 ;;
    --deb) [ $# -ge 2 ] || die "--deb needs a path"; deb="$2"; shift 2 ;;
    --deb=*) deb="${1#--deb=}"; shift ;;
    --source) [ $# -ge 2 ] || die "--source needs a folder"; source="$2"; shift 2 ;;
    --source=*) source="${1#--source=}"; shift ;;
    -*) die "unknown option $1 (see --help)" ;;
    *)
      if [ -z "$rubric" ]; then rubric="$1"
      elif [ -z "$out" ]; then out="$1"
      else die "unexpected argument $1 (see --help)"
      fi
      shift ;;
  esac
done
[ -n "$rubric" ] && [ -n "$out" ] || { usage >&2; exit 2; }
[ -f "$rubric" ] || die "$rubric: no such rubric file"
case "$out" in *.zip) ;; *) die "$out: the archive's name must end in .zip" ;; esac
for tool in python3 zip unzip dpkg-deb sha256sum git tar gzip; do
  command -v "$tool" >/dev/null || die "$tool is not installed (Debian package: ${tool/sha256sum/coreutils})"
done

here=$(cd "$(dirname "$0")" && pwd)
out=$(realpath -m "$out")
work=$(mktemp -d "${TMPDIR:-/tmp}/farm-autograder.XXXXXX")
trap 'rm -rf "$work"' EXIT
stage="$work/stage"
mkdir -p "$stage/lab" "$stage/grading" "$work/empty"

# The .deb: given, or made from the build folder the way tests/deploy/lib/common.sh does.
if [ -z "$deb" ]; then
  build="${FARM_BUILD_DIR:-$here/../../build/release}"
  [ -f "$build/CPackConfig.cmake" ] || die "no --deb given and no configured build folder at $build"
  echo "making the .deb with cpack in $build"
  (cd "$build" && cpack -G DEB -B "$work/deb" >"$work/cpack.log" 2>&1) || { cat "$work/cpack.log" >&2; die "cpack failed"; }
  deb=$(ls "$work"/deb/renderfarm_*.deb | head -1)
fi
[ -f "$deb" ] || die "$deb: no such .deb"
deb_name=$(basename "$deb")
[[ "$deb_name" =~ ^renderfarm_[A-Za-z0-9.+~-]+_[a-z0-9]+\.deb$ ]] || die "$deb: not a renderfarm_VERSION_ARCH.deb"
[ "$(dpkg-deb -f "$deb" Package)" = renderfarm ] || die "$deb: not the renderfarm package"

# The source, for images that build the farm (setup.sh on Ubuntu 24.04): the checkout's files
# that git tracks or would track (new files not yet committed included, ignored ones such as
# build/ left out), so that it is the tree the .deb was built from. Owned by root in the tar, as
# Gradescope unpacks it as root. Its project version must be the .deb's, or the archive would
# carry two different farms.
source="${source:-$here/../..}"
[ -d "$source" ] || die "--source $source: no such folder"
source=$(cd "$source" && pwd -P)
[ "$(git -C "$source" rev-parse --show-toplevel 2>/dev/null)" = "$source" ] \
  || die "$source: not the top of a git checkout (--source)"
source_version=$(sed -n 's/^project([A-Za-z0-9_]* VERSION \([0-9.]*\).*/\1/p' "$source/CMakeLists.txt" 2>/dev/null | head -1)
deb_version=$(dpkg-deb -f "$deb" Version)
[ -n "$source_version" ] || die "$source/CMakeLists.txt: no project(... VERSION ...): not the farm's source"
[ "${deb_version%%-*}" = "$source_version" ] \
  || die "$source is version $source_version, the .deb $deb_version: give the checkout the .deb was built from (--source)"
(cd "$source" && git ls-files -z --cached --others --exclude-standard \
  | while IFS= read -r -d '' file; do [ -f "$file" ] && printf '%s\0' "$file"; done \
  | tar --null -T - --owner=0 --group=0 --numeric-owner -czf "$work/farm-source.tar.gz") \
  || die "could not make the source tarball of $source"
tar -tzf "$work/farm-source.tar.gz" >"$work/source.list"
grep -qxF deploy/install-deps.sh "$work/source.list" \
  || die "$source: the source tarball has no deploy/install-deps.sh (setup.sh needs it)"

# The references are rendered by the farm the .deb holds, so the scene hashes and the pictures
# are exactly what the installed farm computes on Gradescope.
dpkg-deb -x "$deb" "$work/debroot"
farm="$work/debroot/usr/bin/farm"
"$farm" --version >/dev/null || die "the .deb's farm does not run here (build the archive on the Debian 12 machine that built it)"

# Which files the archive must carry, and the folder they are all confined to. Printed as
# NUL-separated fields: the base folder, the asset root, the rubric, then each job (absolute).
python3 - "$rubric" >"$work/layout" <<'EOF'
import json, os, sys

def refuse(message):
    sys.stderr.write(f"make-autograder.sh: {message}\n")
    sys.exit(2)

rubric = os.path.realpath(sys.argv[1])  # as farm reads it: links resolved
folder = os.path.dirname(rubric)
try:
    with open(rubric, encoding="utf-8") as f:
        doc = json.load(f)
except (OSError, ValueError) as e:
    refuse(f"{sys.argv[1]}: not a JSON rubric: {e}")
if not isinstance(doc, dict) or not isinstance(doc.get("tasks"), list):
    refuse(f"{sys.argv[1]}: not a rubric (no \"tasks\" list); farm grade --help")
root = os.path.realpath(os.path.join(folder, str(doc.get("asset_root", "."))))

def inside(path, top):
    return os.path.commonpath([path, top]) == top

# The base: the rubric's folder, or its asset root when that holds the folder.
if inside(folder, root):
    base = root
elif inside(root, folder):
    base = folder
else:
    refuse(f"{sys.argv[1]}: asset_root {root} neither holds nor lies in the rubric's folder {folder}")
jobs = []
for task in doc["tasks"]:
    if not isinstance(task, dict) or not isinstance(task.get("job"), str):
        continue  # farm grade names the error precisely
    job = os.path.realpath(os.path.join(folder, task["job"]))
    if not inside(job, base):
        refuse(f"{sys.argv[1]}: task '{task.get('name')}': its job {job} lies outside {base}, "
               "the rubric's folder (or asset_root); the archive carries files under it only")
    if job not in jobs:
        jobs.append(job)
for path in [base, root, rubric] + jobs:
    if "\n" in path:
        refuse(f"{path!r}: a file name with a line break")
sys.stdout.write("\0".join([base, root, rubric] + jobs) + "\0")
EOF
mapfile -d '' fields <"$work/layout"
base="${fields[0]}" root="${fields[1]}" rubric_abs="${fields[2]}"
jobs=("${fields[@]:3}")
rubric_rel="lab/${rubric_abs#"$base"/}"
# The rubric's path goes into run_autograder's text: plain characters only.
[[ "$rubric_rel" =~ ^[A-Za-z0-9._/-]+$ ]] || die "$rubric_abs: use a path of letters, digits, '.', '_', '-' and '/' for the rubric"

# Renders every reference once (an empty class of students), validating the rubric, its jobs and
# their models on the way: farm grade refuses a model outside asset_root, naming it.
echo "rendering the references of $rubric with $("$farm" --version)"
"$farm" grade "$rubric_abs" "$work/empty" --out "$work/rendered" >"$work/render.log" 2>&1 \
  || { cat "$work/render.log" >&2; die "farm grade could not render the references (above)"; }

copy_in() {  # SOURCE DEST_IN_STAGE: a copy of the file a link leads to, never the link
  mkdir -p "$(dirname "$stage/$2")"
  cp -L --preserve=mode "$1" "$stage/$2"
}
copy_in "$rubric_abs" "$rubric_rel"
for job in "${jobs[@]}"; do copy_in "$job" "lab/${job#"$base"/}"; done

# farm grade laid each job out in references/<hash>/job/: the job file (its own name, at the top)
# and every file its models read, named relative to the asset root. Those names are the files
# to carry; a top-level name that is not a file in the asset root is the job's own copy.
root_rel=""
[ "$root" = "$base" ] || root_rel="${root#"$base"/}/"
job_names=$(for job in "${jobs[@]}"; do basename "$job"; done)
for reference in "$work"/rendered/references/*/; do
  reference="${reference%/}"
  hash=$(basename "$reference")
  mkdir -p "$stage/grading/references/$hash"
  cp "$reference/reference.exr" "$reference/reference.png" "$stage/grading/references/$hash/"
  while IFS= read -r -d '' file; do
    name="${file#"$reference"/job/}"
    if [ -f "$root/$name" ]; then
      copy_in "$root/$name" "lab/$root_rel$name"
    elif [[ "$name" != */* ]] && grep -qxF "$name" <<<"$job_names"; then
      continue
    else
      die "$root/$name: farm read it for a reference but it is not there now"
    fi
  done < <(find "$reference/job" -type f -print0)
done
(cd "$stage/grading" && find references -type f -name 'reference.*' -print0 | sort -z | xargs -0 sha256sum >references.sha256)

sed "s|@DEB@|$deb_name|g" "$here/setup.sh" >"$stage/setup.sh"
sed "s|@RUBRIC@|$rubric_rel|g" "$here/run_autograder" >"$stage/run_autograder"
chmod 755 "$stage/setup.sh" "$stage/run_autograder"
cp "$deb" "$stage/$deb_name"
cp "$work/farm-source.tar.gz" "$stage/farm-source.tar.gz"

# The copy must reproduce the scene hashes, or Gradescope would render: grade it here against a
# copy of the shipped references and see that no new one appears.
cp -r "$stage/grading" "$work/check"
"$farm" grade "$stage/$rubric_rel" "$work/empty" --out "$work/check" >"$work/check.log" 2>&1 \
  || { cat "$work/check.log" >&2; die "the archive's copy of the rubric does not grade (above)"; }
[ "$(ls "$work/check/references")" = "$(ls "$stage/grading/references")" ] \
  || die "the archive's copy of the rubric has other scene hashes than the original: a file is missing from lab/"

# Zipped from inside the stage: every entry relative; checked, since Gradescope unpacks as root.
rm -f "$out.part"
(cd "$stage" && zip -q -r -X "$out.part" setup.sh run_autograder "$deb_name" farm-source.tar.gz lab grading)
if unzip -Z1 "$out.part" | grep -qE '^/|(^|/)\.\.(/|$)'; then
  rm -f "$out.part"
  die "an entry of the archive is not a relative path inside it"
fi
mv "$out.part" "$out"
echo "wrote $out: $(unzip -Z1 "$out" | grep -cv '/$') files, $(du -h "$out" | cut -f1);" \
  "rubric $rubric_rel, $(ls "$stage/grading/references" | wc -l) pre-rendered references"
