"""Decodes the bytes of every type written by `lcm_peer write-bytes` with the generated Python
modules, re-encodes them and checks the bytes are identical. Usage: check_python_bindings.py DIR TYPES..."""
import importlib
import sys

directory, types = sys.argv[1], sys.argv[2:]
failed = False
for name in types:
    module = importlib.import_module("whiskeye." + name)
    cls = getattr(module, name)
    with open(f"{directory}/{name}.bin", "rb") as f:
        data = f.read()
    msg = cls.decode(data)
    if msg.encode() != data:
        print(f"BAD {name}")
        failed = True
    else:
        print(f"OK {name}")
sys.exit(1 if failed else 0)
