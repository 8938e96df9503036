#!/bin/bash
# A report its directory's filesystem cannot hold says so before any work: exit 2, one line naming the
# directory and the room it needs, the old report untouched, nothing left beside it. On a 2 MB tmpfs in a user
# and mount namespace of its own (unshare); skipped (77) where one cannot be made.
#   report_needs_room.sh path/to/stepwise
if ! unshare -rm true 2>/dev/null; then
  echo "report_needs_room: skipped: unshare -rm is not permitted here (no user namespaces)"
  exit 77
fi
exec unshare -rm bash -s "$1" <<'INNER'
d=$(mktemp -d)
mount -t tmpfs -o size=2m none "$d" || { echo "report_needs_room: skipped: cannot mount a tmpfs"; exit 77; }
mkdir "$d/r" && echo '{"files": ["keep"]}' > "$d/r/.stepwise-report.json" && echo old > "$d/r/keep"
err=$("$1" report --quick --out "$d/r" 2>&1 >/dev/null)
rc=$?
fail=0
[ "$rc" = 2 ] || { echo "FAIL: exit status $rc, expected 2"; fail=1; }
[ "$(printf '%s\n' "$err" | wc -l)" = 1 ] || { echo "FAIL: more than one line (work started?):"; printf '%s\n' "$err" | head -5; fail=1; }
case "$err" in *"$d"*"MB free"*) ;; *) echo "FAIL: the message names neither the directory nor the room: $err"; fail=1 ;; esac
[ "$(cat "$d/r/keep")" = old ] || { echo "FAIL: the old report was touched"; fail=1; }
[ "$(ls -A "$d")" = r ] || { echo "FAIL: left beside it: $(ls -A "$d")"; fail=1; }
echo "report_needs_room: $err"
exit $fail
INNER
