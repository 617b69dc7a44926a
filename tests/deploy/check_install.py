#!/usr/bin/env python3
"""Install-layout and unit checks for the deployment (docs/deployment.md).

  check_install.py CHECK --build DIR --prefix PREFIX --sysconfdir FULL_SYSCONFDIR

Installs with `cmake --install DIR --prefix PREFIX` into a temporary DESTDIR (the build's own prefix
does not matter: units are configured at install time).

CHECK is one of:
  layout    `cmake --install` into a DESTDIR puts every binary, unit, config, the jar, the Python
            package (which imports) and the system integration files where docs/deployment.md says,
            and the units point at them.
  verify    `systemd-analyze verify` accepts every installed unit without a single warning.
  security  `systemd-analyze security --offline=true`: slamd and camerad expose <= 3.0 ("OK" or better);
            whiskerd and based are printed (docs/deployment.md quotes them) and must stay <= 3.0 too;
            whiskeye-viewer, a web server, <= 2.0.
  defaults  the installed vita-sim, run from a folder outside any source or build tree without
            --robot or --whiskerd-config, finds the configs installed in <sysconfdir>/whiskeye; with
            robot.yaml removed it exits non-zero naming the path it tried.
  deb       `cpack -G DEB` builds a package whose contents (`dpkg-deb -c`) are the /usr + /etc layout
            with copyright, changelog and a man page per program, whose control files mark the
            configs as conffiles, with postinst, prerm and postrm and a real Maintainer.
Exit status 0 only if every assertion held; each failure is printed on its own line.
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile

DAEMONS = ["whiskerd", "camerad", "based", "slamd", "whiskeye-viewer"]
TOOLS = ["rcp-plant", "vita-sim", "vita-eval", "whiskeye-lcm-spy", "whiskeye-logcheck", "whiskeye-calibrate"]
UNITS = [d + ".service" for d in DAEMONS] + ["whiskeye-can0.service", "whiskeye.target"]
CONFIGS = ["whiskerd.yaml", "camerad.yaml", "based.yaml", "slam.yaml", "robot.yaml", "rcp.yaml"]
PYTHON_MODULES = ["__init__", "log", "channels", "vita_map_t", "vita_pose_t", "image_t"]
EXPOSURE_LIMIT = 3.0
# A daemon that serves HTTP is held to a lower limit.
EXPOSURE_LIMITS = {"whiskeye-viewer": 2.0}

failures = []


def fail(msg):
    failures.append(msg)
    print("FAIL: " + msg)


def run(cmd, **kw):
    return subprocess.run(cmd, capture_output=True, text=True, **kw)


def expected_files(prefix, sysconfdir):
    rel = lambda p: p.lstrip("/")
    files = [f"{prefix}/bin/{b}" for b in DAEMONS + TOOLS]
    files += [f"{prefix}/lib/systemd/system/{u}" for u in UNITS]
    files += [f"{prefix}/lib/sysusers.d/whiskeye.conf", f"{prefix}/lib/sysctl.d/60-whiskeye-lcm.conf",
              f"{prefix}/lib/udev/rules.d/60-whiskeye-gpio.rules", f"{prefix}/share/java/whiskeye_types.jar",
              f"{prefix}/share/doc/whiskeye/deployment.md", f"{prefix}/share/whiskeye/worlds/aliased_arena.yaml",
              f"{sysconfdir}/default/whiskeye"]
    # The Python package where Debian's python3 finds it (docs/python.md), and its example.
    files += [f"{prefix}/lib/python3/dist-packages/whiskeye/{m}.py" for m in PYTHON_MODULES]
    files += [f"{prefix}/share/doc/whiskeye/examples/plot_run.py"]
    files += [f"{sysconfdir}/whiskeye/{c}" for c in CONFIGS]
    return [rel(f) for f in files]


def install(build, destdir, prefix):
    r = run(["cmake", "--install", build, "--prefix", prefix], env=dict(os.environ, DESTDIR=destdir))
    if r.returncode != 0:
        fail("cmake --install failed: " + r.stderr.strip()[-500:])
        return False
    return True


def unit_text(destdir, prefix, unit):
    with open(os.path.join(destdir, prefix.lstrip("/"), "lib/systemd/system", unit)) as f:
        return f.read()


def check_layout(a, destdir):
    for f in expected_files(a.prefix, a.sysconfdir):
        path = os.path.join(destdir, f)
        if not os.path.isfile(path):
            fail("not installed: /" + f)
        elif "/bin/" in f and not os.access(path, os.X_OK):
            fail("not executable: /" + f)
    for d in DAEMONS:
        text = unit_text(destdir, a.prefix, d + ".service")
        exec_start = re.search(r"^ExecStart=(\S+)(.*)$", text, re.M)
        if not exec_start or exec_start.group(1) != f"{a.prefix}/bin/{d}":
            fail(f"{d}.service: ExecStart is not {a.prefix}/bin/{d}")
        for cfg in re.findall(r"(/\S+\.yaml)", exec_start.group(2) if exec_start else ""):
            if not os.path.isfile(os.path.join(destdir, cfg.lstrip("/"))):
                fail(f"{d}.service: config {cfg} is not installed")
        if f"EnvironmentFile=-{a.sysconfdir}/default/whiskeye" not in text:
            fail(f"{d}.service: no EnvironmentFile={a.sysconfdir}/default/whiskeye")
        for key in ["Type=notify", "Restart=on-failure", "User=whiskeye", "NoNewPrivileges=yes",
                    "ProtectSystem=strict", "PrivateTmp=yes", "ProtectHome=yes"]:
            if key not in text.splitlines():
                fail(f"{d}.service: missing {key}")
        if not re.search(r"^WatchdogSec=\d", text, re.M):
            fail(f"{d}.service: no WatchdogSec=")
        if not re.search(r"^RestrictAddressFamilies=", text, re.M):
            fail(f"{d}.service: no RestrictAddressFamilies=")
    # Every service is bounded in memory and tasks (docs/deployment.md, "Resource limits").
    for unit in [d + ".service" for d in DAEMONS] + ["whiskeye-can0.service"]:
        lines = unit_text(destdir, a.prefix, unit).splitlines()
        for key in ["MemoryMax=", "TasksMax="]:
            if not any(l.startswith(key) and len(l) > len(key) for l in lines):
                fail(f"{unit}: no {key}")
    whiskerd = unit_text(destdir, a.prefix, "whiskerd.service").splitlines()
    for key in ["CPUSchedulingPolicy=fifo", "LimitMEMLOCK=infinity", "DeviceAllow=char-gpiochip rw",
                "CapabilityBoundingSet=", "Requires=whiskeye-can0.service"]:
        if key not in whiskerd:
            fail("whiskerd.service: missing " + key)
    if not any(l.startswith("LimitRTPRIO=") for l in whiskerd):
        fail("whiskerd.service: no LimitRTPRIO=")
    if "DeviceAllow=char-video4linux rw" not in unit_text(destdir, a.prefix, "camerad.service").splitlines():
        fail("camerad.service: no DeviceAllow for the camera")
    if "StateDirectory=slamd" not in unit_text(destdir, a.prefix, "slamd.service").splitlines():
        fail("slamd.service: no StateDirectory=slamd")
    # The viewer is optional: in the target only once enabled, and serving this host only.
    viewer = unit_text(destdir, a.prefix, "whiskeye-viewer.service").splitlines()
    target = unit_text(destdir, a.prefix, "whiskeye.target")
    if "whiskeye-viewer" in target:
        fail("whiskeye.target names whiskeye-viewer: the viewer must be optional")
    for key in ["WantedBy=whiskeye.target", "PartOf=whiskeye.target"]:
        if key not in viewer:
            fail("whiskeye-viewer.service: missing " + key)
    if not any(l.startswith("ExecStart=") and "--listen 127.0.0.1:" in l for l in viewer):
        fail("whiskeye-viewer.service: does not listen on 127.0.0.1 only")
    can0 = unit_text(destdir, a.prefix, "whiskeye-can0.service")
    if "Before=whiskerd.service" not in can0 or "fd on" not in can0:
        fail("whiskeye-can0.service: not a CAN FD bring-up ordered before whiskerd")
    # The environment file keeps LCM on the robot and asks for no more buffer than the sysctl allows.
    with open(os.path.join(destdir, a.sysconfdir.lstrip("/"), "default/whiskeye")) as f:
        env = f.read()
    url = re.search(r'^LCM_DEFAULT_URL="(\S+)"$', env, re.M)
    # Sourced by a shell it must give the same value systemd reads.
    sourced = run(["bash", "-c", "set -a; . \"$1\"; printf %s \"$LCM_DEFAULT_URL\"", "-",
                   os.path.join(destdir, a.sysconfdir.lstrip("/"), "default/whiskeye")]).stdout
    if not url or sourced != url.group(1):
        fail(f"environment file: LCM_DEFAULT_URL not quoted or not shell-sourceable (shell read {sourced!r})")
    with open(os.path.join(destdir, a.prefix.lstrip("/"), "lib/sysctl.d/60-whiskeye-lcm.conf")) as f:
        sysctl = f.read()
    rmem = re.search(r"^net\.core\.rmem_max\s*=\s*(\d+)", sysctl, re.M)
    # Java's LCM (lcm-spy) ignores recv_buf_size: it gets the default, which must hold camera frames.
    rmem_default = re.search(r"^net\.core\.rmem_default\s*=\s*(\d+)", sysctl, re.M)
    if not rmem_default or int(rmem_default.group(1)) < 4 * 1024 * 1024:
        fail("sysctl.d: net.core.rmem_default missing or below 4 MiB (lcm-spy would drop camera frames)")
    if not url or "ttl=0" not in url.group(1):
        fail("environment file: LCM_DEFAULT_URL without ttl=0")
    elif not rmem:
        fail("sysctl.d: no net.core.rmem_max")
    else:
        buf = re.search(r"recv_buf_size=(\d+)", url.group(1))
        if not buf or int(buf.group(1)) > int(rmem.group(1)):
            fail("LCM recv_buf_size missing or above net.core.rmem_max")
    # The installed package imports with the standard library alone (Debian has no python3-lcm).
    site = os.path.join(destdir, a.prefix.lstrip("/"), "lib/python3/dist-packages")
    r = run(["/usr/bin/python3", "-c", "import sys; sys.modules['lcm'] = None; import whiskeye, whiskeye.log; "
             "print(whiskeye.channels.TYPES['VITA_MAP'])"], env=dict(os.environ, PYTHONPATH=site,
                                                                      PYTHONDONTWRITEBYTECODE="1"))
    if r.returncode != 0 or r.stdout.strip() != "vita_map_t":
        fail("the installed Python package does not import: " + (r.stdout + r.stderr).strip()[-300:])
    if any("__pycache__" in d for d, _, _ in os.walk(site)):
        fail("__pycache__ installed with the Python package")
    with open(os.path.join(destdir, a.prefix.lstrip("/"), "lib/sysusers.d/whiskeye.conf")) as f:
        if not re.search(r"^u whiskeye ", f.read(), re.M):
            fail("sysusers.d: no whiskeye user")


def staged_units(a, destdir, out):
    """The installed units with ExecStart pointing into DESTDIR (verify checks that the program
    exists), otherwise byte for byte what was installed."""
    os.makedirs(out, exist_ok=True)
    for u in UNITS:
        text = unit_text(destdir, a.prefix, u)
        text = re.sub(r"^ExecStart=" + re.escape(a.prefix + "/bin/"),
                      "ExecStart=" + os.path.join(destdir, a.prefix.lstrip("/"), "bin") + "/", text, flags=re.M)
        with open(os.path.join(out, u), "w") as f:
            f.write(text)
    return [os.path.join(out, u) for u in UNITS]


def check_verify(a, destdir):
    units = staged_units(a, destdir, os.path.join(destdir, "verify"))
    r = run(["systemd-analyze", "verify"] + units)
    output = (r.stdout + r.stderr).strip()
    print(f"systemd-analyze verify: exit {r.returncode}" + (":\n" + output if output else ", no warnings"))
    if r.returncode != 0:
        fail(f"systemd-analyze verify exited {r.returncode}")
    # verify exits 0 on ignored (unknown or unparsable) settings, which would silently weaken a unit.
    if output:
        fail("systemd-analyze verify printed warnings")


def check_security(a, destdir):
    units = staged_units(a, destdir, os.path.join(destdir, "security"))
    for d in DAEMONS:
        path = [u for u in units if u.endswith("/" + d + ".service")][0]
        r = run(["systemd-analyze", "security", "--offline=true", "--no-pager", path])
        m = re.search(r"Overall exposure level for \S+: (\d+(?:\.\d+)?) (\w+)", r.stdout + r.stderr)
        if not m:
            fail(f"{d}: no exposure level in systemd-analyze security output: {(r.stdout + r.stderr)[-300:]}")
            continue
        level, rating = float(m.group(1)), m.group(2)
        print(f"{d}.service: exposure {level} {rating}")
        limit = EXPOSURE_LIMITS.get(d, EXPOSURE_LIMIT)
        if level > limit:
            fail(f"{d}.service: exposure {level} > {limit}")


def check_deb(a, destdir):
    out = os.path.join(destdir, "deb")
    os.makedirs(out)
    r = run(["cpack", "-G", "DEB", "--config", os.path.join(a.build, "CPackConfig.cmake"), "-B", out])
    debs = [f for f in os.listdir(out) if f.endswith(".deb")]
    if r.returncode != 0 or not debs:
        fail("cpack -G DEB failed: " + (r.stdout + r.stderr).strip()[-800:])
        return
    deb = os.path.join(out, debs[0])
    listing = run(["dpkg-deb", "-c", deb]).stdout
    paths = set(re.sub(r"^\./", "", line.split()[-1]).rstrip("/") for line in listing.splitlines() if line.strip())
    # Symlinks print as "name -> target".
    paths |= set(re.sub(r"^\./", "", line.split()[-3]) for line in listing.splitlines() if " -> " in line)
    for f in expected_files("/usr", "/etc"):
        if f not in paths:
            fail("not in the .deb: /" + f)
    if any(p.startswith("usr/local") for p in paths):
        fail("the .deb installs under /usr/local")
    info = run(["dpkg-deb", "-I", deb, "conffiles"]).stdout.split()
    for c in ["/etc/default/whiskeye"] + ["/etc/whiskeye/" + c for c in CONFIGS]:
        if c not in info:
            fail("not a conffile: " + c)
    # The packaged units name the packaged paths.
    root = os.path.join(destdir, "root")
    run(["dpkg-deb", "-x", deb, root])
    for d in DAEMONS:
        with open(os.path.join(root, "usr/lib/systemd/system", d + ".service")) as f:
            text = f.read()
        if f"ExecStart=/usr/bin/{d} " not in text or "EnvironmentFile=-/etc/default/whiskeye" not in text:
            fail(f"{d}.service in the .deb does not run /usr/bin/{d} with /etc/default/whiskeye")
    field = run(["dpkg-deb", "-f", deb, "Package", "Depends"]).stdout
    print(field.strip())
    if "Package: whiskeye" not in field:
        fail("package name is not whiskeye")
    control = run(["dpkg-deb", "-I", deb]).stdout
    for script in ["postinst", "prerm", "postrm"]:
        if script not in control:
            fail(f"no {script} (service user, sysctl; units stopped on removal, state purged)")
    # Debian's documentation: copyright, changelog, a man page per program (help2man at build time).
    for f in ["usr/share/doc/whiskeye/copyright", "usr/share/doc/whiskeye/changelog.Debian.gz"]:
        if f not in paths:
            fail("not in the .deb: /" + f)
    for d in DAEMONS:
        if f"usr/share/man/man8/{d}.8.gz" not in paths:
            fail(f"no man page /usr/share/man/man8/{d}.8.gz")
    for t in TOOLS:
        if f"usr/share/man/man1/{t}.1.gz" not in paths:
            fail(f"no man page /usr/share/man/man1/{t}.1.gz")
    maintainer = run(["dpkg-deb", "-f", deb, "Maintainer"]).stdout.strip()
    if not re.fullmatch(r"[^<>]+ <[^@<>\s]+@[^@<>\s]+\.[a-z]+>", maintainer) or "localhost" in maintainer:
        fail("not a real Maintainer: " + maintainer)
    print(f"{debs[0]}: {len(paths)} entries")


def check_defaults(a, destdir):
    root = os.path.join(destdir, a.prefix.lstrip("/"))
    confdir = os.path.join(destdir, a.sysconfdir.lstrip("/"), "whiskeye")
    work = os.path.join(destdir, "work")
    os.makedirs(work)
    sim = [os.path.join(root, "bin/vita-sim"), "--world", os.path.join(root, "share/whiskeye/worlds/aliased_arena.yaml"),
           "--duration", "1", "--output", "sim.lcmlog", "--candump", "sim.candump", "-q"]
    r = run(sim, cwd=work)
    if r.returncode != 0:
        fail(f"installed vita-sim without --robot/--whiskerd-config exited {r.returncode}: {r.stderr.strip()[-500:]}")
    elif not os.path.getsize(os.path.join(work, "sim.lcmlog")) or not os.path.getsize(os.path.join(work, "sim.candump")):
        fail("installed vita-sim wrote an empty log or candump log")
    robot = os.path.join(confdir, "robot.yaml")
    os.remove(robot)
    r = run(sim, cwd=work)
    if r.returncode == 0 or robot not in r.stderr or "--robot" not in r.stderr:
        fail(f"without {robot}: exit {r.returncode}, expected an error naming it and --robot: {r.stderr.strip()[-500:]}")
    else:
        print("without robot.yaml: " + r.stderr.strip())


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("check", choices=["layout", "verify", "security", "defaults", "deb"])
    p.add_argument("--build", required=True)
    p.add_argument("--prefix", required=True)
    p.add_argument("--sysconfdir", required=True)
    a = p.parse_args()
    a.prefix = a.prefix.rstrip("/")
    destdir = tempfile.mkdtemp(prefix="whiskeye-install-")
    try:
        if a.check == "deb":
            check_deb(a, destdir)
        elif install(a.build, destdir, a.prefix):
            checks = {"layout": check_layout, "verify": check_verify, "security": check_security,
                      "defaults": check_defaults}
            checks[a.check](a, destdir)
    finally:
        shutil.rmtree(destdir, ignore_errors=True)
    if failures:
        print(f"{len(failures)} failure(s)")
        return 1
    print("all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
