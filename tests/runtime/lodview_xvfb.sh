#!/bin/sh
# lodview_xvfb.sh XVFB_RUN SCREEN PROGRAM [ARG...]: runs PROGRAM under `XVFB_RUN -a -s "-screen 0 SCREEN"`
# and exits with PROGRAM's own exit status, not xvfb-run's. xvfb-run returns the command's status
# only when its own clean-up succeeds: when removing its temporary Xauthority folder fails it exits
# 5 after the command has finished, which would turn a lodview result into an unrelated failure.
# The status is therefore written to a file by a shell inside the X session and read back here.
# When PROGRAM never ran (Xvfb did not start, xvfb-run missing), the exit is 125 with a message, a
# code no lodview check accepts.
set -u
if [ $# -lt 3 ]; then
    echo "usage: lodview_xvfb.sh XVFB_RUN SCREEN PROGRAM [ARG...]" >&2
    exit 2
fi
xvfb_run=$1
screen=$2
shift 2
status_file=$(mktemp "${TMPDIR:-/tmp}/lodview-status.XXXXXX") || exit 125
trap 'rm -f "$status_file"' EXIT
: >"$status_file"
# $0 of the inner shell is the status file, "$@" the program and its arguments.
# shellcheck disable=SC2016 # expanded by the inner shell
"$xvfb_run" -a -s "-screen 0 $screen" sh -c '"$@"; s=$?; echo "$s" >"$0"; exit "$s"' "$status_file" "$@"
xvfb_status=$?
status=$(cat "$status_file")
case "$status" in
'' | *[!0-9]*)
    echo "lodview_xvfb.sh: $1 did not run: $xvfb_run exited $xvfb_status" >&2
    exit 125
    ;;
esac
if [ "$xvfb_status" != "$status" ]; then
    echo "lodview_xvfb.sh: $xvfb_run exited $xvfb_status after $1 exited $status; $1's status counts" >&2
fi
exit "$status"
