#!/usr/bin/env python3
"""Converts one record of the CWRU bearing data set (a MATLAB .mat file) into a CSV recording
that follows edgekf's data contract (README, "Data formats").

Where the data come from: the Case Western Reserve University Bearing Data Center
(https://engineering.case.edu/bearingdatacenter), which publishes one .mat file per record
(normal baseline, and drive-end/fan-end faults seeded by EDM, 12 kHz and 48 kHz). A copy of the
12 kHz files, named like `normal_0_97.mat` or `12k_Drive_End_IR007_0_105.mat`, is mirrored at
https://github.com/yyxyz/CaseWesternReserveUniversityData. The data set states no licence, so
no recording, excerpt or converted CSV is committed to this repository: fetch the .mat files
yourself, convert them outside the repository, and point the tests or `--data` at the CSVs.

    python3 -m venv /tmp/venv-cwru && /tmp/venv-cwru/bin/pip install -r tools/requirements-cwru.txt
    /tmp/venv-cwru/bin/python tools/cwru_to_csv.py normal_0_97.mat --out 097_48k.csv \\
        --channel DE=n1_ay --channel FE=n11_ay
    /tmp/venv-cwru/bin/python tools/cwru_to_csv.py normal_0_97.mat --decimate 4 --out 097.csv \\
        --channel DE=n1_ay --channel FE=n11_ay
    /tmp/venv-cwru/bin/python tools/cwru_to_csv.py 12k_Drive_End_IR007_0_105.mat \\
        --start 0 --duration 5 --out 105_first5s.csv

What is in a file: variables `X<nnn>_DE_time` (drive-end housing accelerometer),
`X<nnn>_FE_time` (fan-end housing), `X<nnn>_BA_time` (base plate; not in every file), all in g,
one column each, and `X<nnn>RPM` (the shaft speed noted during the test). `<nnn>` is the record
number, but a file may also hold another record's variables (098 is said to hold X099 too), so
for each sensor the variable whose number matches the record is taken (the record number is the
last number in the file name, or `--record`), else the only one there is, with a notice.

The sample rate: 12 kHz for the 12 kHz drive-end and fan-end fault files, 48 kHz for the
48 kHz drive-end files and for the normal baseline records 097-100. The baseline is 48 kHz
although it is usually filed with the 12 kHz data: read at 12 kHz, record 097 has lines at
quarter orders of the shaft speed (7.48, 14.97, 22.45 Hz ... for a 29.93 Hz shaft), which
vanish at 48 kHz, where only the integer orders remain, as in the 12 kHz fault record 105 and
the 48 kHz record 109 (0 hp both), and 097 has as many samples as the 48 kHz record 109
(243938: 5.08 s). So without `--rate` the rate is 48000 Hz for records 97-100 and files whose
name starts with `48k`, else 12000 Hz, and the choice goes to stderr. `--decimate N` writes
every N-th sample after a linear-phase anti-alias FIR (Kaiser window: flat to 0.8 of the new
Nyquist frequency, 80 dB down at it), e.g. `--decimate 4` puts the 48 kHz baseline on the 12 kHz
fault records' clock; the filter's delay is compensated, and the first and last ~25 output
samples carry its start-up (the record is padded with its mean).

What is written: a header row, then one row per sample, comma-separated. The first column is
`t` in seconds, t = k / fs with k the sample's index in the record (so a cut made with
`--start` keeps the record's own clock; with `--decimate N`, fs is the output rate and k
counts output samples). `t` is written as the shortest decimal that reads back to the exact
double k / fs, so the reader sees no jitter; the channels follow in m/s^2 (g x 9.80665) with
9 significant digits (the recordings come from a 16-bit recorder). Channels are named by
`--channel SENSOR=NAME` (SENSOR is DE, FE or BA), in the order given; the default is
`DE=n1_ay`. `--start` and `--duration` are seconds on the output clock.

Safety: the output's folder must exist; an existing output is refused unless `--force`, and the
input is never overwritten, whatever the spelling. The CSV is written to a temporary file in
the output's folder and renamed into place when complete, so an error or an interrupt leaves
no half-written file. The record's RPM and sample count go to stderr.

Exit codes: 0 done; 1 an unreadable file, a missing variable or a bad output path, with one line
on stderr; 2 a usage error (argparse's message).
"""

import argparse
import math
import os
import re
import sys
import tempfile

G = 9.80665  # standard gravity, m/s^2 per g
SENSORS = ("DE", "FE", "BA")
SENSOR_VAR = re.compile(r"^X(\d+)_(DE|FE|BA)_time$")
RPM_VAR = re.compile(r"^X(\d+)RPM$")
FORBIDDEN_IN_NAME = re.compile(r'[,"\r\n]')


class Failure(Exception):
    """A one-line error for the user; exit code 1."""


def notice(msg):
    print(f"cwru_to_csv: {msg}", file=sys.stderr)


def parse_channel(spec):
    if "=" not in spec:
        raise argparse.ArgumentTypeError(f"{spec!r}: expected SENSOR=NAME, e.g. DE=n1_ay")
    sensor, name = (s.strip() for s in spec.split("=", 1))
    sensor = sensor.upper()
    if sensor not in SENSORS:
        raise argparse.ArgumentTypeError(f"{spec!r}: sensor must be one of {', '.join(SENSORS)}")
    if not name or FORBIDDEN_IN_NAME.search(name):
        raise argparse.ArgumentTypeError(
            f"{spec!r}: the channel name must be non-empty and hold no comma, quote or line break")
    if name == "t":
        raise argparse.ArgumentTypeError(f"{spec!r}: 't' is the time column")
    return sensor, name


def non_negative(text):
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number")
    if not (math.isfinite(v) and v >= 0.0):
        raise argparse.ArgumentTypeError(f"{text!r} must be a finite number >= 0")
    return v


def positive(text):
    v = non_negative(text)
    if v <= 0.0:
        raise argparse.ArgumentTypeError(f"{text!r} must be > 0")
    return v


def record_number(path, override):
    if override is not None:
        return override
    digits = re.findall(r"\d+", os.path.splitext(os.path.basename(path))[0])
    return int(digits[-1]) if digits else None


def pick(variables, pattern, wanted_sensor, record, what, path):
    """The variable for one sensor (or the RPM): the one numbered like the record, else the only one."""
    found = []
    for key in variables:
        m = pattern.match(key)
        if m and (wanted_sensor is None or m.group(2) == wanted_sensor):
            found.append((int(m.group(1)), key))
    found.sort()
    if not found:
        present = ", ".join(sorted(k for k in variables if not k.startswith("__"))) or "none"
        raise Failure(f"{path}: no {what} variable in the file (variables: {present})")
    matching = [key for number, key in found if number == record]
    if matching:
        return matching[0]
    if len(found) == 1:
        key = found[0][1]
        if record is None:
            notice(f"{path}: no record number in the file name; using {key}, the only {what} variable")
        else:
            notice(f"{path}: no {what} variable numbered {record}; using {key}, the only one")
        return key
    names = ", ".join(key for _, key in found)
    if record is None:
        raise Failure(f"{path}: several {what} variables ({names}) and no record number in the "
                      f"file name; give --record")
    raise Failure(f"{path}: no {what} variable numbered {record} among {names}; give --record")


def same_file(a, b):
    try:
        return os.path.samefile(a, b)
    except OSError:
        return os.path.realpath(a) == os.path.realpath(b)


def main(argv=None):
    ap = argparse.ArgumentParser(
        description="Convert one CWRU bearing .mat record to an edgekf CSV (t in s, channels in m/s^2).")
    ap.add_argument("input", help="the CWRU .mat file")
    ap.add_argument("--out", required=True, help="the CSV to write")
    ap.add_argument("--channel", action="append", type=parse_channel, metavar="SENSOR=NAME",
                    help="map a sensor (DE, FE, BA) to a channel name; repeatable; default DE=n1_ay")
    ap.add_argument("--rate", type=positive, default=None,
                    help="the record's sample rate, Hz (default: 48000 for records 97-100 and files "
                         "named 48k*, else 12000)")
    ap.add_argument("--decimate", type=int, default=1, metavar="N",
                    help="write every N-th sample after an anti-alias FIR (default 1: all samples)")
    ap.add_argument("--start", type=non_negative, default=0.0,
                    help="first sample at k = round(start * fs), s (default 0)")
    ap.add_argument("--duration", type=positive, default=None,
                    help="round(duration * fs) samples from --start, s (default: to the end)")
    ap.add_argument("--record", type=int, default=None,
                    help="the record number, when the file name does not end with it")
    ap.add_argument("--force", action="store_true", help="overwrite an existing output (never the input)")
    args = ap.parse_args(argv)
    if args.decimate < 1:
        ap.error(f"--decimate {args.decimate}: must be 1 or more")

    channels = args.channel or [("DE", "n1_ay")]
    names = [name for _, name in channels]
    dup = {n for n in names if names.count(n) > 1}
    if dup:
        ap.error(f"channel name(s) {', '.join(sorted(dup))} given twice")
    sensors = [s for s, _ in channels]
    dup = {s for s in sensors if sensors.count(s) > 1}
    if dup:
        ap.error(f"sensor(s) {', '.join(sorted(dup))} mapped twice")

    try:
        run(args, channels)
    except Failure as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    return 0


def check_output(inp, out, force):
    folder = os.path.dirname(os.path.abspath(out))
    if not os.path.isdir(folder):
        raise Failure(f"{out}: the output's folder {folder} does not exist")
    if os.path.exists(out) or os.path.islink(out):
        if os.path.exists(out) and same_file(inp, out):
            raise Failure(f"{out}: this is the input {inp} (the same file)")
        if not force:
            raise Failure(f"{out}: exists; give --force to overwrite it")
        if os.path.isdir(out):
            raise Failure(f"{out}: is a folder")
    return folder


def run(args, channels):
    inp, out = args.input, args.out
    if not os.path.isfile(inp):
        raise Failure(f"{inp}: no such file")
    folder = check_output(inp, out, args.force)

    import numpy as np
    import scipy.io

    try:
        mat = scipy.io.loadmat(inp)
    except Exception as e:  # scipy raises several types for a bad file
        msg = str(e).splitlines()[0] if str(e) else type(e).__name__
        raise Failure(f"{inp}: not a readable MATLAB file ({msg})")

    record = record_number(inp, args.record)
    cols = []
    for sensor, name in channels:
        key = pick(mat, SENSOR_VAR, sensor, record, f"{sensor}_time", inp)
        x = np.asarray(mat[key], dtype=np.float64).reshape(-1)
        notice(f"{name} <- {key} ({x.size} samples, g -> m/s^2)")
        cols.append((name, key, x))
    lengths = {x.size for _, _, x in cols}
    if len(lengths) != 1:
        detail = ", ".join(f"{key} {x.size}" for _, key, x in cols)
        raise Failure(f"{inp}: the channels differ in length ({detail})")
    n_record = lengths.pop()

    try:
        rpm_key = pick(mat, RPM_VAR, None, record, "RPM", inp)
        rpm = float(np.asarray(mat[rpm_key]).reshape(-1)[0])
        notice(f"RPM {rpm:g} ({rpm_key}), shaft {rpm / 60.0:.4f} Hz")
    except Failure:
        notice(f"{inp}: no RPM variable in the file; RPM unknown")

    fs_in = args.rate
    if fs_in is None:
        fs_in = default_rate(inp, record)
    n_dec = args.decimate
    fs = fs_in / n_dec
    series = [x * G for _, _, x in cols]
    if n_dec > 1:
        series = [decimate(x, n_dec) for x in series]
        notice(f"decimated by {n_dec}: {fs_in:g} Hz -> {fs:g} Hz, {series[0].size} samples")
    n_out = series[0].size
    k0 = int(round(args.start * fs))
    if k0 >= n_out:
        raise Failure(f"{inp}: --start {args.start:g} s is past the record's end "
                      f"({n_out} samples, {n_out / fs:g} s at {fs:g} Hz)")
    if args.duration is None:
        k1 = n_out
    else:
        k1 = k0 + int(round(args.duration * fs))
        if k1 > n_out:
            raise Failure(f"{inp}: --start {args.start:g} s --duration {args.duration:g} s runs past "
                          f"the record's end ({n_out} samples, {n_out / fs:g} s at {fs:g} Hz)")
        if k1 == k0:
            raise Failure(f"{inp}: --duration {args.duration:g} s is less than one sample")

    data = [x[k0:k1] for x in series]
    bad = sum(int(np.count_nonzero(~np.isfinite(d))) for d in data)
    if bad:
        notice(f"{bad} non-finite value(s) written as empty cells")

    fd, tmp = tempfile.mkstemp(prefix="." + os.path.basename(out) + ".", suffix=".tmp", dir=folder)
    try:
        with os.fdopen(fd, "w", newline="\n", encoding="utf-8") as f:
            f.write(",".join(["t"] + [name for name, _, _ in cols]) + "\n")
            chunk = []
            for i, k in enumerate(range(k0, k1)):
                # repr: the shortest decimal that reads back to the exact double k / fs.
                cells = [repr(k / fs)]
                for d in data:
                    v = d[i]
                    cells.append("%.9g" % v if math.isfinite(v) else "")
                chunk.append(",".join(cells))
                if len(chunk) == 8192:
                    f.write("\n".join(chunk) + "\n")
                    chunk.clear()
            if chunk:
                f.write("\n".join(chunk) + "\n")
        os.chmod(tmp, 0o644 & ~current_umask())
        if args.force:
            os.replace(tmp, out)
        else:
            try:  # atomically refuses an output created meanwhile
                os.link(tmp, out)
                os.unlink(tmp)
            except FileExistsError:
                raise Failure(f"{out}: exists; give --force to overwrite it")
            except OSError:  # no hard links on this file system
                if os.path.exists(out):
                    raise Failure(f"{out}: exists; give --force to overwrite it")
                os.replace(tmp, out)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise

    n = k1 - k0
    notice(f"{inp}: {n_record} samples in the record ({n_record / fs_in:g} s at {fs_in:g} Hz); "
           f"wrote {n} rows, t = {k0 / fs:g} .. {(k1 - 1) / fs:g} s, to {out}")


# Records sampled at 48 kHz whose file names need not say so: the normal baseline (module docstring).
BASELINE_48K = range(97, 101)


def default_rate(path, record):
    name = os.path.basename(path)
    if name.lower().startswith("48k"):
        notice(f"rate 48000 Hz (the file name says 48k; give --rate to override)")
        return 48000.0
    if record in BASELINE_48K:
        notice(f"rate 48000 Hz (record {record} is a normal baseline record, sampled at 48 kHz; "
               f"give --rate to override, --decimate 4 for 12 kHz)")
        return 48000.0
    notice("rate 12000 Hz (give --rate to override)")
    return 12000.0


def decimate(x, n):
    """Every n-th sample after a zero-phase Kaiser FIR, 80 dB down at the new Nyquist frequency."""
    import numpy as np
    import scipy.signal as sg

    nyq_out = 0.5 / n  # in cycles per input sample
    numtaps, beta = sg.kaiserord(80.0, 0.2 * nyq_out * 2.0)  # transition 0.8..1.0 of nyq_out
    numtaps |= 1  # odd: a whole-sample delay, which resample_poly removes
    h = sg.firwin(numtaps, 0.9 * nyq_out * 2.0, window=("kaiser", beta))
    bad = ~np.isfinite(x)
    if bad.any():
        raise Failure(f"{int(bad.sum())} non-finite value(s): cannot decimate")
    return sg.resample_poly(x, 1, n, window=h, padtype="mean")


def current_umask():
    mask = os.umask(0)
    os.umask(mask)
    return mask


if __name__ == "__main__":
    try:
        sys.exit(main())
    except KeyboardInterrupt:
        print("error: interrupted; no output written", file=sys.stderr)
        sys.exit(130)
    except BrokenPipeError:
        sys.exit(0)
