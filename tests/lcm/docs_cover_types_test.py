"""docs/lcm-channels.md documents every type and every field of lcmtypes/*.lcm."""
import pathlib
import re
import sys

root = pathlib.Path(sys.argv[1])
doc = (root / "docs/lcm-channels.md").read_text()
missing = []
for lcm in sorted((root / "lcmtypes").glob("*.lcm")):
    text = re.sub(r"//.*", "", lcm.read_text())
    struct = re.search(r"struct\s+(\w+)", text).group(1)
    if f"`{struct}`" not in doc:
        missing.append(f"type {struct}")
    body = text[text.index("{") + 1 : text.rindex("}")]
    for decl in body.split(";"):
        decl = decl.strip()
        if not decl or decl.startswith("const"):
            continue
        field = re.match(r"[\w.]+\s+(\w+)", decl).group(1)
        if not re.search(rf"`{field}[`\[,]", doc) and f"`{field}`" not in doc:
            missing.append(f"{struct}.{field}")
if missing:
    print("undocumented in docs/lcm-channels.md:", ", ".join(missing))
    sys.exit(1)
print("PASS")
