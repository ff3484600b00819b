#!/usr/bin/env bash
# Regenerates the shipped replays with the project's own path code (world seed 1).
#   replays/make-replays.sh [path/to/ambience]
set -euo pipefail
cd "$(dirname "$0")"
amb="${1:-../build/bin/ambience}"

"$amb" replay make --mode drive --road highway --speed 30 --duration 90 --time 12 \
  --name highway-drive --description "Highway drive at 30 m/s, midday (the default replay)" \
  --out highway-drive.json
"$amb" replay make --mode drive --road mountain --speed 18 --duration 75 \
  --time 16.5 --name mountain-drive \
  --description "Winding mountain road at 18 m/s, late afternoon" \
  --out mountain-drive.json
"$amb" replay make --mode fly --speed 80 --altitude 60 --clearance 25 --turn-radius 500 \
  --flight-seed 3 --start -2000,1500 --heading 60 --duration 60 --time 9 \
  --name low-flight --description "Low flight at 80 m/s, 60 m above the terrain, morning" \
  --out low-flight.json
"$amb" replay make --mode fly --speed 250 --altitude 120 --clearance 40 --turn-radius 1500 \
  --flight-seed 7 --start 0,0 --heading 135 --cuts 1 --cut-jump 4000 --duration 60 --time 14 \
  --name stress-flight \
  --description "High-speed stress flight at 250 m/s with a camera cut (teleport), afternoon" \
  --out stress-flight.json
"$amb" replay make --mode static --at -4200,-5000 --height 4 --heading 120 --pitch 5 \
  --duration 144 --time 0 --time-rate 600 --name day-timelapse \
  --description "Stationary camera through a full day at time rate 600" \
  --out day-timelapse.json
"$amb" replay make --mode fly --speed 120 --altitude 80 --clearance 25 --turn-radius 700 \
  --flight-seed 11 --start 1000000,-1000000 --heading 200 --duration 40 --time 17 \
  --name far-flight \
  --description "Flight at 120 m/s a million metres from the origin (precision), late afternoon" \
  --out far-flight.json
"$amb" replay make --mode static --at -4866,4537 --height 28 --heading 180 --pitch -50 \
  --duration 12 --time 19.3 --name ravine-dusk \
  --description "Stationary camera 28 m above a gully in ravine country, looking down, at dusk" \
  --out ravine-dusk.json
# Held out: no setting is tuned on these two (docs/TUNING.md "Held-out replays"); the bench and
# `ambience tune` evaluate on them.
"$amb" replay make --mode drive --road mountain --seed 7 --speed 16 --duration 60 --time 16.6 \
  --latitude 52 --day 290 --max-lateral-accel 3 --name dusk-mountain-held-out \
  --description "Held out of tuning: a dusk drive on the mountain road of another world (seed 7), sun 5 degrees up" \
  --out dusk-mountain-held-out.json
"$amb" replay make --mode fly --speed 70 --altitude 35 --clearance 20 --turn-radius 250 \
  --flight-seed 23 --start 3000000,2000000 --heading 300 --duration 50 --time 10.5 \
  --name hairpin-flight-held-out \
  --description "Held out of tuning: a low flight in tight turns 3.6 million metres from the origin, 70 m/s" \
  --out hairpin-flight-held-out.json
