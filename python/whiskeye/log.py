"""Reads LCM log files (lcm-logger, vita-sim, slamd --replay) in pure Python.

Debian 12 packages no Python module for LCM, and none is needed to read a log: the format is a
sequence of events, each a 28-byte big-endian header -- sync word 0xEDA1DA01 (u32), event number
(i64), timestamp in microseconds (i64), channel length (i32), data length (i32) -- then the channel
name and the message bytes (https://lcm-proj.github.io/lcm/content/log-file-format.html).

    import whiskeye.log
    for event in whiskeye.log.read("run.lcmlog"):
        if event.channel == whiskeye.channels.VITA_POSE:
            pose = event.decode()          # a whiskeye.vita_pose_t
            print(event.timestamp, pose.x, pose.y)

A damaged log is read as far as it can be, as slamd and vita-eval read it (common/src/bus.cpp):
  - garbage between events (a disk error, a bad copy): the reader skips to the next sync word that
    starts a plausible event, as LCM's own reader resynchronises;
  - a last event cut off (a logger killed mid-write, a full disk): iteration stops before it.
Either way nothing is raised: when iteration ends, `Reader.damage` says what was skipped (its
`str()` is one line, like vita-eval's) and a `LogDamageWarning` is issued once. With
`read(path, strict=True)` the first damage raises `LogError` instead. Event times are returned as
written (slamd's reader also replaces a time that is out of line with both neighbours; this one
does not).
"""

import importlib
import mmap
import os
import re
import stat
import struct
import warnings

from . import channels

SYNC = 0xEDA1DA01
_SYNC_BYTES = struct.pack(">I", SYNC)
_HEADER = struct.Struct(">Iqqii")  # sync, event number, timestamp (us), channel length, data length
HEADER_SIZE = _HEADER.size  # 28
MAX_CHANNEL_LENGTH = 1000  # what LCM's reader accepts (and common/src/bus.cpp)
# Where a plausible event may start: the sync word, 16 bytes, a channel length below 1024 and a data
# length that is not negative. Searched for in C, so that garbage of sync words (every 4 bytes a
# candidate) is skipped at the speed of the regex engine; each hit is then checked by _check.
_CANDIDATE = re.compile(re.escape(_SYNC_BYTES) + rb".{16}\x00\x00[\x00-\x03].[\x00-\x7f]", re.DOTALL)

__all__ = ["read", "Reader", "Event", "LogDamage", "LogError", "LogDamageWarning", "UnknownChannelError",
           "DecodeError", "type_for_channel", "SYNC", "HEADER_SIZE"]


class LogError(Exception):
    """The log cannot be read (strict mode: it is damaged)."""


class LogDamageWarning(UserWarning):
    """Issued once at the end of a damaged log's iteration; the message is Reader.damage."""


class UnknownChannelError(LookupError):
    """Event.decode() on a channel that is not one of the stack's (whiskeye.channels.TYPES)."""


class DecodeError(ValueError):
    """The bytes on a channel are not a message of the channel's type."""


def type_for_channel(channel):
    """The generated class of the LCM type a channel carries, e.g. whiskeye.vita_pose_t; None if unknown."""
    name = channels.TYPES.get(channel)
    if name is None:
        return None
    try:
        module = importlib.import_module(__package__ + "." + name)
    except ModuleNotFoundError:
        raise ImportError("%s.%s: the LCM types are generated at build time: import whiskeye from the build "
                          "(PYTHONPATH=build/python) or the installed package" % (__package__, name)) from None
    return getattr(module, name)


def _open_log(path):
    """A descriptor of the regular file at `path` and its size. Refuses, as common/src/bus.cpp does, what is
    no log file: a FIFO (opened without waiting for a writer), a device, a directory, a /proc file."""
    fd = os.open(path, os.O_RDONLY | os.O_CLOEXEC | os.O_NONBLOCK)  # a FIFO with no writer: no wait
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise LogError("%s: cannot open the LCM log for reading: not a regular file" % path)
        if st.st_size == 0 and os.pread(fd, 1, 0):
            raise LogError("%s: cannot open the LCM log for reading: not a regular file "
                           "(it reports 0 bytes but holds data)" % path)
    except BaseException:
        os.close(fd)
        raise
    return fd, st.st_size


class Event:
    """One log event: `channel` (str), `timestamp` (int, microseconds since the epoch, when it was
    logged), `data` (bytes, the encoded message), `eventnum` (int) and `offset` (its byte offset)."""

    __slots__ = ("eventnum", "timestamp", "channel", "data", "offset")

    def __init__(self, eventnum, timestamp, channel, data, offset=0):
        self.eventnum = eventnum
        self.timestamp = timestamp
        self.channel = channel
        self.data = data
        self.offset = offset

    def decode(self):
        """The message, decoded with the type the channel carries (whiskeye.channels.TYPES).

        Raises UnknownChannelError for a channel the stack does not define, and DecodeError when the
        bytes are not that type (wrong fingerprint or too short)."""
        cls = type_for_channel(self.channel)
        if cls is None:
            raise UnknownChannelError("%s: not a channel of the stack (whiskeye.channels.TYPES)" % self.channel)
        try:
            return cls.decode(self.data)
        except (ValueError, struct.error) as e:
            raise DecodeError("%s at byte %d: not a %s (%s)" % (self.channel, self.offset, cls.__name__, e)) from None

    def __repr__(self):
        return "Event(%d, %d, %r, <%d bytes>)" % (self.eventnum, self.timestamp, self.channel, len(self.data))


class LogDamage:
    """What a reader skipped: the first problem (with its byte offset), bytes skipped in how many
    places, and whether the last event was cut off."""

    def __init__(self, path):
        self.path = path
        self.first_problem = ""
        self.skipped_bytes = 0
        self.places = 0
        self.truncated_tail = False

    def __bool__(self):
        return self.places > 0

    def __str__(self):
        if not self:
            return ""
        s = "%s; %d bytes skipped in %d place%s" % (self.first_problem, self.skipped_bytes, self.places,
                                                     "" if self.places == 1 else "s")
        if self.truncated_tail:
            s += ", the last event cut off"
        return s


class Reader:
    """An iterable over a log's events (see the module's docstring for damaged logs)."""

    def __init__(self, path, strict=False):
        self.path = os.fspath(path)
        self.strict = strict
        self.damage = LogDamage(self.path)
        self.events = 0
        os.close(_open_log(self.path)[0])  # fail now, naming the file, if it is none to read

    def _check(self, buf, size, at):
        """(total size, None) for a plausible event at `at`; else (0, (reason, truncated))."""
        if size - at < HEADER_SIZE:
            return 0, ("truncated LCM log: incomplete event header at byte %d (file size %d)" % (at, size), True)
        sync, _, _, channel_len, data_len = _HEADER.unpack_from(buf, at)
        if sync != SYNC:
            return 0, ("corrupt LCM log: no event sync word at byte %d" % at, False)
        if channel_len <= 0 or channel_len >= MAX_CHANNEL_LENGTH:
            return 0, ("corrupt LCM log: channel length %d in the event at byte %d" % (channel_len, at), False)
        if data_len < 0:
            return 0, ("corrupt LCM log: data length %d in the event at byte %d" % (data_len, at), False)
        total = HEADER_SIZE + channel_len + data_len
        if size - at < total:
            return 0, ("truncated LCM log: the event at byte %d needs %d bytes, the file has %d left"
                       % (at, total, size - at), True)
        return total, None

    def __iter__(self):
        fd, size = _open_log(self.path)
        try:
            if size == 0:
                return
            with mmap.mmap(fd, 0, access=mmap.ACCESS_READ) as buf:
                yield from self._events(buf, size)
        finally:
            os.close(fd)
        if self.damage:
            warnings.warn(LogDamageWarning(str(self.damage)), stacklevel=2)

    def _events(self, buf, size):
        pos = 0
        while pos < size:
            total, problem = self._check(buf, size, pos)
            if problem is not None:
                reason, truncated = problem
                if self.strict:
                    raise LogError("%s: %s" % (self.path, reason))
                if not self.damage.first_problem:
                    self.damage.first_problem = "%s: %s" % (self.path, reason)
                self.damage.places += 1
                at = pos + 1
                while True:
                    hit = _CANDIDATE.search(buf, at)
                    if hit is None:
                        self.damage.skipped_bytes += size - pos
                        self.damage.truncated_tail = truncated
                        return
                    at = hit.start()
                    total, _ = self._check(buf, size, at)
                    if total:
                        break
                    at += 1
                self.damage.skipped_bytes += at - pos
                pos = at
            _, eventnum, timestamp, channel_len, data_len = _HEADER.unpack_from(buf, pos)
            start = pos + HEADER_SIZE
            channel = buf[start:start + channel_len].decode("utf-8", errors="replace")
            data = buf[start + channel_len:start + channel_len + data_len]
            self.events += 1
            yield Event(eventnum, timestamp, channel, data, pos)
            pos += total


def read(path, strict=False):
    """The events of the LCM log at `path`, in file order: `for event in whiskeye.log.read(path)`.

    Opening fails at once if the file cannot be read (OSError) or is no log file (LogError: a FIFO, a
    device, a directory, a /proc file; never waiting for a FIFO's writer). A damaged log is read as far
    as it can be (see the module docstring); strict=True raises LogError at the first damage instead."""
    return Reader(path, strict=strict)
