#!/usr/bin/env python3
"""Validates JSON documents against a schema of ours (draft 2020-12) with python3-jsonschema.

usage: validate_schema.py SCHEMA FILE...                  each FILE is one JSON document
       validate_schema.py SCHEMA --node-extension NAME FILE...
                                                         every node's extensions[NAME] in each
                                                         .gltf/.glb FILE (at least one must exist)
Prints one line per problem and exits 1 if there is any. glTFProperty.schema.json (referenced by
extension schemas) resolves to the core glTF rule it states: an object whose extensions and extras
members are objects / anything.
"""
import json
import struct
import sys

import jsonschema

try:  # jsonschema >= 4.18 resolves $ref through `referencing`
    import referencing
except ImportError:  # Debian 12's python3-jsonschema 4.10: the older RefResolver
    referencing = None

GLTF_PROPERTY = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "$id": "glTFProperty.schema.json",
    "type": "object",
    "properties": {"extensions": {"type": "object"}, "extras": {}},
}


def load_gltf(path):
    data = open(path, "rb").read()
    if data[:4] == b"glTF":
        length, kind = struct.unpack_from("<II", data, 12)
        if kind != 0x4E4F534A:
            raise ValueError(path + ": first GLB chunk is not JSON")
        return json.loads(data[20:20 + length])
    return json.loads(data)


def main(argv):
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    schema = json.load(open(argv[1]))
    jsonschema.Draft202012Validator.check_schema(schema)
    if referencing is not None:
        registry = referencing.Registry().with_resource(
            "glTFProperty.schema.json", referencing.Resource.from_contents(GLTF_PROPERTY))
        validator = jsonschema.Draft202012Validator(schema, registry=registry)
    else:
        resolver = jsonschema.RefResolver.from_schema(
            schema, store={"glTFProperty.schema.json": GLTF_PROPERTY})
        validator = jsonschema.Draft202012Validator(schema, resolver=resolver)
    files = argv[2:]
    extension = None
    if files[0] == "--node-extension":
        extension, files = files[1], files[2:]
    problems = 0
    for path in files:
        if extension:
            nodes = load_gltf(path).get("nodes", [])
            docs = [(f"{path}: /nodes/{i}/extensions/{extension}", n["extensions"][extension])
                    for i, n in enumerate(nodes) if extension in n.get("extensions", {})]
            if not docs:
                print(f"{path}: no node has {extension}")
                problems += 1
        else:
            docs = [(path, json.load(open(path)))]
        for where, doc in docs:
            for error in validator.iter_errors(doc):
                pointer = "/" + "/".join(str(p) for p in error.absolute_path)
                print(f"{where}: {pointer}: {error.message}")
                problems += 1
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
