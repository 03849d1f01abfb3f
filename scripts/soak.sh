#!/usr/bin/env bash
# GUI soak test (not in the default CI run): the viewer under Xvfb for MINUTES (default 10) of
# random input (clicks and drags on panels and image, wheel, keys), with the viewer's RSS sampled
# every 10 s. Reports a crash (exit status and the last messages), RSS over time and every
# warning/error line the viewer printed. Exit 1 when the viewer died.
# Usage: bash scripts/soak.sh [MINUTES] [SCENE] (after a build in build/).
set -uo pipefail
cd "$(dirname "$0")/.."
MINUTES=${1:-10}
SCENE=${2:-assets/scenes/torch-in-mist.json}
OUT=build/soak
mkdir -p $OUT
export CANDELA_CACHE_DIR=${CANDELA_CACHE_DIR:-$PWD/build/test-cache}
W=1500 H=820
KEYS=(space Tab Escape Left Right Up Down 1 2 3 r f w c h plus minus BackSpace Return 0 5 9 period ctrl+z ctrl+shift+z)
TYPED=(0 1 -1 1e30 nan 0.5 abc 99999 -0.001 1e-30 inf)
run() {
  build/app/candela "$SCENE" >$OUT/viewer.log 2>&1 &
  VIEWER=$!
  sleep 8
  END=$(( $(date +%s) + MINUTES * 60 ))
  NEXT_SAMPLE=0
  RANDOM=1
  echo "seconds rss_mb" >$OUT/rss.txt
  START=$(date +%s)
  while [ "$(date +%s)" -lt $END ]; do
    if ! kill -0 $VIEWER 2>/dev/null; then break; fi
    NOW=$(date +%s)
    if [ $NOW -ge $NEXT_SAMPLE ]; then
      echo "$((NOW - START)) $(( $(awk '/VmRSS/{print $2}' /proc/$VIEWER/status 2>/dev/null || echo 0) / 1024 ))" >>$OUT/rss.txt
      NEXT_SAMPLE=$((NOW + 10))
    fi
    X=$((RANDOM % W)) Y=$((RANDOM % H))
    case $((RANDOM % 8)) in
      0|1) xdotool mousemove $X $Y click 1 ;;
      2) xdotool mousemove $X $Y mousedown 1 mousemove $(((X + RANDOM % 200) % W)) $(((Y + RANDOM % 100) % H)) mouseup 1 ;;
      3) xdotool mousemove $X $Y click $((4 + RANDOM % 2)) ;;
      4) xdotool mousemove $X $Y mousedown 3 mousemove $(((X + 50) % W)) $Y mouseup 3 ;;
      5) xdotool key --clearmodifiers "${KEYS[RANDOM % ${#KEYS[@]}]}" ;;
      6) xdotool mousemove $X $Y keydown ctrl click 1 keyup ctrl ;;  # the guide inspector
      7) xdotool type --delay 5 -- "${TYPED[RANDOM % ${#TYPED[@]}]}" ;;
    esac
    sleep 0.05
  done
  if kill -0 $VIEWER 2>/dev/null; then
    kill $VIEWER; wait $VIEWER 2>/dev/null
    echo "soak: the viewer survived $MINUTES minutes"
    STATUS=0
  else
    wait $VIEWER; CODE=$?
    echo "soak: THE VIEWER DIED (exit $CODE) after $(( $(date +%s) - START )) s; last messages:"
    tail -20 $OUT/viewer.log
    STATUS=1
  fi
  echo "RSS (MB) over time:"; awk 'NR>1{printf "  %5d s %6d MB\n", $1, $2}' $OUT/rss.txt
  echo "messages (warnings, errors, rejected edits):"; grep -iE "warn|error|reject" $OUT/viewer.log | sort | uniq -c | sort -rn | head -20
  return $STATUS
}
# Under Xvfb, this script runs itself again with --inner (xvfb-run's /bin/sh drops exported functions).
if [ "${3:-}" = "--inner" ]; then
  run
  exit $?
fi
xvfb-run -a -s "-screen 0 ${W}x${H}x24" bash "$0" "$MINUTES" "$SCENE" --inner
