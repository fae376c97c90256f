#!/usr/bin/env python3
"""grpc.health.v1.Health/Check learnt from a server's reflection alone, as grpcurl does it.

No .proto file and no generated health stubs: the script lists the server's services through
grpc.reflection.v1alpha.ServerReflection, fetches the file descriptor that defines
grpc.health.v1.Health (and the files it imports), builds the request and response classes from
those descriptors, and calls Check once for each --check SERVICE ("" is the server as a whole).

  health_reflection.py --server HOST:PORT [--check ""] [--check farm.v1.Worker] ...

Prints one line per listed service and one per check:

  service grpc.health.v1.Health
  check "" SERVING
  check "no.such.Service" error NOT_FOUND: <the server's message>

Exit 0 when reflection answered and described the service (whatever the checks said), 1 if not.
"""
import argparse
import json
import queue
import sys

import grpc
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
from grpc_reflection.v1alpha import reflection_pb2, reflection_pb2_grpc

HEALTH = "grpc.health.v1.Health"


class Reflection:
    """One ServerReflectionInfo stream, asked one question at a time."""

    def __init__(self, channel, timeout):
        self._requests = queue.Queue()  # the stream's requests; None ends them
        stub = reflection_pb2_grpc.ServerReflectionStub(channel)
        self._responses = stub.ServerReflectionInfo(iter(self._requests.get, None), timeout=timeout)

    def ask(self, **request):
        self._requests.put(reflection_pb2.ServerReflectionRequest(**request))
        response = next(self._responses)
        if response.HasField("error_response"):
            error = response.error_response
            raise LookupError(f"reflection: {error.error_message} (code {error.error_code})")
        return response

    def close(self):
        self._requests.put(None)
        self._responses.cancel()

    def services(self):
        return [s.name for s in self.ask(list_services="").list_services_response.service]

    def files(self, **request):
        """The FileDescriptorProtos the reply carries."""
        reply = self.ask(**request).file_descriptor_response
        return [descriptor_pb2.FileDescriptorProto.FromString(b) for b in reply.file_descriptor_proto]


def pool_with(reflection, symbol):
    """A descriptor pool holding the file that defines `symbol` and, first, every file it imports."""
    pool = descriptor_pool.DescriptorPool()
    known = {f.name: f for f in reflection.files(file_containing_symbol=symbol)}
    added = set()

    def add(name):
        if name in added:
            return
        if name not in known:  # an import the reply left out: ask for it by name
            for f in reflection.files(file_by_filename=name):
                known.setdefault(f.name, f)
        for dependency in known[name].dependency:
            add(dependency)
        pool.Add(known[name])
        added.add(name)

    for name in list(known):
        add(name)
    return pool


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--server", required=True, help="HOST:PORT")
    parser.add_argument("--check", action="append", default=[], metavar="SERVICE",
                        help='a service to call Check for ("" is the server as a whole); repeatable')
    parser.add_argument("--timeout", type=float, default=60.0,
                        help="seconds each call may take (a bound, not an expectation)")
    args = parser.parse_args()

    with grpc.insecure_channel(args.server) as channel:
        reflection = Reflection(channel, args.timeout)
        try:
            services = reflection.services()
            for name in services:
                print(f"service {name}")
            pool = pool_with(reflection, HEALTH)
        except (grpc.RpcError, LookupError, StopIteration) as e:
            print(f"reflection failed: {e}", file=sys.stderr)
            return 1
        finally:
            reflection.close()

        method = pool.FindServiceByName(HEALTH).methods_by_name["Check"]
        request_class = message_factory.GetMessageClass(method.input_type)
        response_class = message_factory.GetMessageClass(method.output_type)
        status_names = method.output_type.fields_by_name["status"].enum_type.values_by_number
        check = channel.unary_unary(f"/{HEALTH}/Check",
                                    request_serializer=request_class.SerializeToString,
                                    response_deserializer=response_class.FromString)
        for service in args.check:
            label = json.dumps(service)
            try:
                response = check(request_class(service=service), timeout=args.timeout)
            except grpc.RpcError as e:
                print(f"check {label} error {e.code().name}: {e.details()}")
                continue
            print(f"check {label} {status_names[response.status].name}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
