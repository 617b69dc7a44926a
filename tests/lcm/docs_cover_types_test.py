"""docs/lcm-channels.md documents every type and every field of lcmtypes/*.lcm."""
import pathlib
import re
import sys

root = pathlib.Path(sys.argv[1])
doc = (root / "docs/lcm-channels.md").read_text()
# Each type's fields must be documented in its own section ("## `type` ..." up to the next "## "),
# not merely named somewhere in the file.
sections = {}
for part in re.split(r"^## ", doc, flags=re.M)[1:]:
    heading = part.splitlines()[0]
    for name in re.findall(r"`(\w+)`", heading):
        sections[name] = part
missing = []
for lcm in sorted((root / "lcmtypes").glob("*.lcm")):
    text = re.sub(r"//.*", "", lcm.read_text())
    struct = re.search(r"struct\s+(\w+)", text).group(1)
    if struct not in sections:
        missing.append(f"type {struct} (no '## `{struct}`' section)")
        continue
    section = sections[struct]
    body = text[text.index("{") + 1 : text.rindex("}")]
    for decl in body.split(";"):
        decl = decl.strip()
        if not decl or decl.startswith("const"):
            continue
        field = re.match(r"[\w.]+\s+(\w+)", decl).group(1)
        if not re.search(rf"`{field}[`\[,]", section):
            missing.append(f"{struct}.{field}")
if missing:
    print("undocumented in docs/lcm-channels.md:", ", ".join(missing))
    sys.exit(1)
print("PASS")
