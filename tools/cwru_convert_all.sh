#!/bin/sh
# Converts every 12 kHz drive-end fault record of the CWRU bearing data and the healthy 097
# (whole, and its two halves) into the CSVs `cargo xtask cwru --dir OUT` runs on, with
# tools/cwru_to_csv.py. The records' licence is unstated: keep OUT outside the repository.
#
#   git clone --depth 1 https://github.com/yyxyz/CaseWesternReserveUniversityData /tmp/cwru-mirror
#   python3 -m venv /tmp/venv-cwru && /tmp/venv-cwru/bin/pip install -r tools/requirements-cwru.txt
#   PYTHON=/tmp/venv-cwru/bin/python tools/cwru_convert_all.sh /tmp/cwru-mirror /tmp/cwru
#
# MIRROR is a folder of the mirror's .mat files (`12k_Drive_End_IR007_0_105.mat`, …,
# `normal_0_97.mat`). Each fault record becomes OUT/<record>.csv with the drive-end channel as
# `n1_ay` and the fan-end one as `n11_ay`; the 0.028 in records (3001–3008) have no fan-end
# channel, so theirs hold `n1_ay` only. 097 is sampled at 48 kHz: it is decimated to 12 kHz,
# and its halves (097a.csv, the baseline's; 097b.csv) are cut at 2.541 s. A CSV already in OUT
# is kept (the converter refuses to replace it), so an interrupted run can be resumed.
# Exit status: 0 when every file converted, 1 otherwise (each failure named on stderr).
set -eu

if [ $# -ne 2 ]; then
    echo "usage: [PYTHON=python3] $0 MIRROR_DIR OUT_DIR" >&2
    exit 2
fi
mirror=$1
out=$2
python=${PYTHON:-python3}
converter=$(cd "$(dirname "$0")" && pwd)/cwru_to_csv.py

[ -d "$mirror" ] || { echo "$0: $mirror: no such folder" >&2; exit 1; }
mkdir -p "$out"
failed=0
converted=0

# convert OUTPUT ARGS…: runs the converter unless OUT/OUTPUT exists.
convert() {
    target=$out/$1
    shift
    if [ -e "$target" ]; then
        echo "$0: $target exists, kept" >&2
        return 0
    fi
    if "$python" "$converter" "$@" --out "$target"; then
        converted=$((converted + 1))
    else
        echo "$0: FAILED: $target" >&2
        failed=$((failed + 1))
    fi
}

found=0
for mat in "$mirror"/12k_Drive_End_*.mat; do
    [ -e "$mat" ] || continue
    found=$((found + 1))
    stem=$(basename "$mat" .mat)
    record=${stem##*_}
    if [ "$record" -ge 3001 ]; then
        convert "$record.csv" "$mat" --channel DE=n1_ay
    else
        convert "$record.csv" "$mat" --channel DE=n1_ay --channel FE=n11_ay
    fi
done
[ "$found" -gt 0 ] || { echo "$0: $mirror holds no 12k_Drive_End_*.mat" >&2; failed=$((failed + 1)); }

healthy=$mirror/normal_0_97.mat
if [ -e "$healthy" ]; then
    both="--channel DE=n1_ay --channel FE=n11_ay"
    # shellcheck disable=SC2086 # the channel flags split on purpose
    convert 097.csv "$healthy" --decimate 4 $both
    # shellcheck disable=SC2086
    convert 097a.csv "$healthy" --decimate 4 --start 0 --duration 2.541 $both
    # shellcheck disable=SC2086
    convert 097b.csv "$healthy" --decimate 4 --start 2.541 --duration 2.541 $both
else
    echo "$0: $healthy: missing (the baseline is learnt from its first half)" >&2
    failed=$((failed + 1))
fi

echo "$0: $converted file(s) converted into $out, $failed failure(s)" >&2
[ "$failed" -eq 0 ]
