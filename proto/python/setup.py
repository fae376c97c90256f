"""Build hook of farm-client: the gRPC stubs are generated from ../farm.proto while the package is
built, never committed. The metadata is in pyproject.toml.

build_py copies farm_client/ into the build folder as usual, then runs
    python -m grpc_tools.protoc -I<proto dir> --python_out=OUT --grpc_python_out=OUT farm.proto
into OUT = <build>/farm_client/_gen/, adds an __init__.py there, and makes the generated
`import farm_pb2` of farm_pb2_grpc.py package-relative. So the stubs always match the .proto of
the checkout the package was built from, and the source tree stays free of generated files
(an editable install is the exception: it generates into farm_client/_gen/, which git ignores).

FARM_PROTO may name another farm.proto (e.g. when building from a copy of this folder alone).
"""
import os
import re
import subprocess
import sys
import tempfile

from setuptools import setup
from setuptools.command.build_py import build_py

HERE = os.path.dirname(os.path.abspath(__file__))
PROTO = os.environ.get("FARM_PROTO") or os.path.join(HERE, os.pardir, "farm.proto")
GENERATED = ("__init__.py", "farm_pb2.py", "farm_pb2_grpc.py")


def generate_stubs(out_dir):
    proto = os.path.abspath(PROTO)
    if not os.path.isfile(proto):
        raise SystemExit(f"farm-client: {proto} not found; the stubs are generated from proto/farm.proto "
                         "of the checkout (build from proto/python inside it, or set FARM_PROTO)")
    os.makedirs(out_dir, exist_ok=True)
    # grpc_tools.protoc adds its own include folder (google/protobuf/timestamp.proto) itself.
    command = [sys.executable, "-m", "grpc_tools.protoc", "-I" + os.path.dirname(proto),
               "--python_out=" + out_dir, "--grpc_python_out=" + out_dir, proto]
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        raise SystemExit(f"farm-client: generating the stubs failed ({' '.join(command)}):\n"
                         f"{result.stdout}{result.stderr}")
    # protoc writes `import farm_pb2 as farm__pb2`, which finds the module only on sys.path; the
    # stubs live in a package, so the import is made relative to it.
    grpc_file = os.path.join(out_dir, "farm_pb2_grpc.py")
    with open(grpc_file, encoding="utf-8") as f:
        text = f.read()
    text, count = re.subn(r"^import farm_pb2 as ", "from . import farm_pb2 as ", text, flags=re.M)
    if count != 1:
        raise SystemExit(f"farm-client: {grpc_file}: expected one `import farm_pb2 as`, found {count}")
    with open(grpc_file, "w", encoding="utf-8") as f:
        f.write(text)
    with open(os.path.join(out_dir, "__init__.py"), "w", encoding="utf-8") as f:
        f.write(f"# Generated from {os.path.basename(proto)} when farm-client was built; do not edit.\n")


class BuildPyWithStubs(build_py):
    """build_py that also generates farm_client/_gen/ from farm.proto."""

    def run(self):
        super().run()
        generate_stubs(self._gen_dir())

    def _gen_dir(self):
        if getattr(self, "editable_mode", False):
            # An editable install imports farm_client from the source tree: the stubs go there.
            return os.path.join(HERE, "farm_client", "_gen")
        return os.path.join(self.build_lib, "farm_client", "_gen")

    def get_outputs(self, include_bytecode=1):
        # Listed so that the wheel's RECORD and `pip uninstall` know the generated files.
        outputs = super().get_outputs(include_bytecode)
        if not getattr(self, "editable_mode", False):
            outputs += [os.path.join(self._gen_dir(), name) for name in GENERATED]
        return outputs


# Nothing is written into the source folder (issue #32: pip's in-tree build left build/ and
# farm_client.egg-info/ beside the code): setuptools' build and egg-info folders go to a temporary
# folder of this build, which the operating system's temporary space cleans up.
SCRATCH = tempfile.mkdtemp(prefix="farm-client-build-")

setup(cmdclass={"build_py": BuildPyWithStubs},
      options={"build": {"build_base": os.path.join(SCRATCH, "build")},
               "egg_info": {"egg_base": SCRATCH}})
