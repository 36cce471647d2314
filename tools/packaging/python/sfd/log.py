# SPDX-License-Identifier: MIT
"""Loads an sfd LCM log into numpy arrays and writes it as CSV.

An sfd log is an LCM log file (the format of lcm-logger; sfd-replay -o and sfd-sim -o write
it): IMU, CAMERA_INFO, FEATURES and TRUTH in, SFD_VERDICT, SFD_STATE and SFD_TIMING out.
Messages are typed by their LCM fingerprint, not by channel name, so renamed channels load too;
events of other types (LCM_SELF_TEST, foreign types) are counted in Log.skipped.

    from sfd.log import load_log
    log = load_log("out.lcmlog")
    v = log["SFD_VERDICT"]
    v["utime"]            # (n,) int64, one entry per message
    v.features["status"]  # (m,) one entry per feature, m = v["num_features"].sum()
    v.features["message"] # (m,) index of the message each feature row belongs to

Per message (Channel.fields): every scalar field as an (n,) array, every fixed-size array
field (position[3], rejected[21], ...) as (n, k). For the types that carry a feature list
(num_features and a CAPACITY constant: feature_frame_t, feature_verdict_t, truth_t, truth_v1_t)
the per-feature arrays are cut to num_features and concatenated in Channel.features, one row per
feature, with "message" (row of the message) and "utime" (its utime). Channel.log_utime holds the
log's own event timestamps (receive or write time, microseconds).

The log format is read here (sync word 0xEDA1DA01, event number, timestamp, channel and data
lengths, big-endian; LCM's documented file format), so no LCM Python binding is needed: the
generated types use only the standard struct module. Only numpy is required.
"""
import collections
import csv
import importlib
import os
import re
import struct

import numpy as np

# Every generated type of the package (the classes lcm-gen wrote, imported by __init__.py).
TYPES = tuple(t for _, t in sorted(vars(importlib.import_module(__package__)).items())
              if isinstance(t, type) and hasattr(t, "_get_packed_fingerprint"))
_BY_FINGERPRINT = {t._get_packed_fingerprint(): t for t in TYPES}
_SYNC = 0xEDA1DA01
_HEADER = struct.Struct(">IqqII")  # sync, event number, timestamp (us), channel len, data len


class LogError(ValueError):
    """The file is not an LCM log (no sync word where an event starts)."""


def read_events(path):
    """Yields (event_number, timestamp_us, channel, data) for every event of the LCM log.

    A last event cut short (a logger stopped mid-write) ends the iteration; the generator's
    return value (StopIteration.value) is then the byte offset where it starts, else None.
    Raises LogError on a bad sync word."""
    with open(path, "rb") as f:
        offset = 0
        while True:
            head = f.read(_HEADER.size)
            if not head:
                return None
            if len(head) >= 4 and struct.unpack(">I", head[:4])[0] != _SYNC:
                raise LogError("%s: no LCM sync word at byte %d (not an LCM log, or corrupt)"
                               % (path, offset))
            if len(head) < _HEADER.size:
                return offset
            _, num, utime, chan_len, data_len = _HEADER.unpack(head)
            body = f.read(chan_len + data_len)
            if len(body) < chan_len + data_len:
                return offset
            channel = body[:chan_len].decode("utf-8", "replace")
            yield num, utime, channel, body[chan_len:]
            offset += _HEADER.size + chan_len + data_len


def _feature_fields(lcm_type):
    """Names of the per-feature list fields of a feature-list type, else ()."""
    if "num_features" not in lcm_type.__slots__ or not hasattr(lcm_type, "CAPACITY"):
        return ()
    sample = lcm_type()
    return tuple(s for s in lcm_type.__slots__
                 if isinstance(getattr(sample, s), (list, tuple))
                 and len(getattr(sample, s)) == lcm_type.CAPACITY)


class Channel:
    """One channel of a log: the messages of one LCM type, as numpy arrays."""

    def __init__(self, name, lcm_type, log_utime, fields, features):
        self.name = name
        self.type = lcm_type
        self.log_utime = log_utime
        self.fields = fields
        self.features = features  # None for types without a feature list

    def __len__(self):
        return len(self.log_utime)

    def __getitem__(self, key):
        return self.fields[key]

    def __repr__(self):
        extra = "" if self.features is None else ", %d features" % len(self.features["message"])
        return "<Channel %s: %d %s%s>" % (self.name, len(self), self.type.__name__, extra)


class Log:
    """A loaded log: channels by name, and what was not loaded."""

    def __init__(self, path, channels, skipped, malformed, truncated_at):
        self.path = path
        self.channels = channels          # name -> Channel, in order of first appearance
        self.skipped = skipped            # channel -> events of a type that is not sfd's
        self.malformed = malformed        # channel -> sfd-typed events that did not decode
        self.truncated_at = truncated_at  # byte offset of a cut-short last event, else None

    def __getitem__(self, name):
        return self.channels[name]

    def __contains__(self, name):
        return name in self.channels

    def __repr__(self):
        return "<Log %s: %s>" % (self.path, ", ".join(repr(c) for c in self.channels.values()))


def _to_array(values):
    arr = np.asarray(values)
    if arr.dtype == object:
        raise ValueError("ragged field")
    return arr


def load_log(path, channels=None):
    """Loads the sfd messages of the LCM log at @p path (all channels, or those named in
    @p channels) into a Log. Raises OSError when the file cannot be read, LogError when it is
    not an LCM log."""
    raw = collections.OrderedDict()  # channel -> (type, [log_utime], [message])
    skipped = collections.Counter()
    malformed = collections.Counter()
    events = read_events(path)
    truncated_at = None
    while True:
        try:
            _, utime, channel, data = next(events)
        except StopIteration as stop:
            truncated_at = stop.value
            break
        if channels is not None and channel not in channels:
            continue
        lcm_type = _BY_FINGERPRINT.get(data[:8])
        if lcm_type is None or (channel in raw and raw[channel][0] is not lcm_type):
            skipped[channel] += 1
            continue
        try:
            msg = lcm_type.decode(data)
        except (ValueError, struct.error):
            malformed[channel] += 1
            continue
        per_feature = _feature_fields(lcm_type)
        if per_feature and not 0 <= msg.num_features <= lcm_type.CAPACITY:
            malformed[channel] += 1
            continue
        raw.setdefault(channel, (lcm_type, [], []))
        raw[channel][1].append(utime)
        raw[channel][2].append(msg)

    loaded = collections.OrderedDict()
    for name, (lcm_type, log_utime, msgs) in raw.items():
        per_feature = _feature_fields(lcm_type)
        fields = {}
        for slot in lcm_type.__slots__:
            if slot in per_feature:
                continue
            fields[slot] = _to_array([getattr(m, slot) for m in msgs])
        features = None
        if per_feature:
            counts = np.array([m.num_features for m in msgs], dtype=np.int64)
            features = {
                "message": np.repeat(np.arange(len(msgs), dtype=np.int64), counts),
                "utime": np.repeat(fields["utime"], counts),
            }
            for slot in per_feature:
                parts = [np.asarray(getattr(m, slot)[:m.num_features]) for m in msgs]
                features[slot] = (np.concatenate(parts) if parts else np.zeros(0))
        loaded[name] = Channel(name, lcm_type, np.asarray(log_utime, dtype=np.int64), fields,
                               features)
    return Log(path, loaded, skipped, malformed, truncated_at)


def _columns(arrays):
    """Flattens {name: (n,) or (n, k)} into CSV column names and (n,) columns."""
    names, cols = [], []
    for name, arr in arrays.items():
        if arr.ndim == 1:
            names.append(name)
            cols.append(arr)
        else:
            for j in range(arr.shape[1]):
                names.append("%s_%d" % (name, j))
                cols.append(arr[:, j])
    return names, cols


def _write_table(path, arrays):
    names, cols = _columns(arrays)
    rows = len(cols[0]) if cols else 0
    with open(path, "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(names)
        lists = [c.tolist() for c in cols]  # Python ints and floats: repr round-trips exactly
        for i in range(rows):
            w.writerow([c[i] for c in lists])
    return rows


def safe_name(channel):
    """File-name stem for a channel name (characters outside [A-Za-z0-9_.-] become '_')."""
    return re.sub(r"[^A-Za-z0-9_.-]", "_", channel) or "_"


def write_csv(log, outdir):
    """Writes every channel of @p log to @p outdir: CHANNEL.csv (one row per message: log_utime,
    then the fields; an array field f[k] as columns f_0 .. f_{k-1}) and, for the feature-list
    types, CHANNEL.features.csv (one row per feature: message, utime, then the per-feature
    fields). Returns [(path, rows)]."""
    os.makedirs(outdir, exist_ok=True)
    written = []
    for name, ch in log.channels.items():
        stem = os.path.join(outdir, safe_name(name))
        table = collections.OrderedDict([("log_utime", ch.log_utime)])
        table.update(ch.fields)
        written.append((stem + ".csv", _write_table(stem + ".csv", table)))
        if ch.features is not None:
            written.append((stem + ".features.csv",
                            _write_table(stem + ".features.csv", ch.features)))
    return written
