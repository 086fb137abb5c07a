# wobble — the two commands people need: `make demo` and `make test`.
#
#   make demo        install what is missing, build (Release), render the table jumping off a cliff
#   make test        install, build (Release), run every test once under Xvfb
#   make asan        every test that needs no display again, in an AddressSanitizer + UBSan build
#                    (CI runs `make test`, then `make asan`)
#   make test-quick  the edit-test loop: build, then every test but the `long` ones
#   make bench       build and run the benchmarks (make bench-build: build them all, run none)
#   make bench-mujoco  the Witkin & Welch step against MuJoCo 2.2.2 (installs libmujoco-dev)
#   make build       configure and build only
#   make deps        install the Debian packages that are missing (as root)
#   make fuzz        build the libFuzzer targets of fuzz/ (clang) and run each FUZZ_SECONDS (60)
#   make clean       remove the build folders and out/
#
# Build folders can be moved: make test BUILD=build-mine ASAN_BUILD=build-mine-asan. Builds go
# through ccache when it is there (CMakeLists.txt); a build folder inside the clone shares the
# cache with every other clone of the same sources.

SHELL := /bin/bash
.ONESHELL:
.SHELLFLAGS := -eu -o pipefail -c

MAKEFLAGS  += --no-print-directory

BUILD      ?= build
ASAN_BUILD ?= build-asan
JOBS       ?= 2
OUT        ?= out/demo

# ffmpeg's libraries encode the videos; the ffmpeg package (ffprobe), python3-pil and chromium
# are the tests' readers of them, programs wobble does not contain; libjs-three is three.js,
# copied into the web preview (--what web) when it is written
PACKAGES := libvtk9-dev libeigen3-dev libceres-dev libopenexr-dev libimath-dev \
            libgtest-dev libgmock-dev libbenchmark-dev xvfb xauth libcli11-dev \
            nlohmann-json3-dev cmake g++ make libpagmo-dev libpng-dev zlib1g-dev \
            pybind11-dev python3-dev python3-numpy python3-pytest python3-matplotlib \
            libopenmpi-dev openmpi-bin ccache ninja-build \
            libavcodec-dev libavformat-dev libavutil-dev libswscale-dev pkgconf ffmpeg python3-pil chromium \
            libtinygltf-dev libjs-three
# only `make fuzz` needs these (libFuzzer is clang's)
FUZZ_PACKAGES := clang libclang-rt-14-dev
# only `make bench-mujoco` needs this (the peer the Witkin & Welch step is measured against)
MUJOCO_PACKAGES := libmujoco-dev


# The sloped-ground drop (simulated only, into table_drop.csv; README's render speed runs the
# same scene): the table (lattice 300 x 100) dropped from 50 onto the ground sloped by -5
# degrees (thesis integrator, dt 0.01, 10 s); tan 5 deg is below the friction cap 0.1, so it
# bounces and settles instead of sliding away.
DEMO_OBJECT   ?= data/table.obj
DEMO_MODES    ?= data/table_modes.def
DEMO_ARGS     ?= --q "0 50 0 0 0 0 0" --integrator thesis --dt 0.01 --duration 10 --ground-slope -5
DEMO_WHAT     ?= frames,filmstrip,charts,vtp,exr,disp
WOBBLE        := $(BUILD)/app/wobble
DEMO_SCRIPT   ?= data/table_cliff.wob  # writes and renders into out/demo (its `output` and `render` lines)
# The 3D scene: data/pot3.obj (a mesh, its lattice fitted, 750 kg in ~400 volume samples) dropped
# from 30 above the ground, tilted 0.34 rad, falling at 60 and spinning at 1.2 rad/s about its axis
DEMO3D_ARGS   ?= --object data/pot3.obj --modes data/pot3_modes.def3 --q "0 30 0 0.3 0 0.15 0 0 0" \
                 --qdot "0 -60 0 0 1.2 0 0 0 0" --duration 4 --dt 0.001 --orbit 30 --elevation 25 \
                 --filmstrip "0 0.4 0.8 1.5 2.5 4" --what frames,filmstrip,charts,vtp,exr,mp4,gltf,web

.PHONY: all deps fuzz-deps configure build demo-build demo test test-quick asan bench-build bench bench-mujoco bench-mpi bench-python fuzz clean

all: build

deps:
	@missing=()
	for p in $(PACKAGES); do
	  if [ "$$(dpkg-query -W -f='$${Status}' "$$p" 2>/dev/null)" != "install ok installed" ]; then
	    missing+=("$$p")
	  fi
	done
	if [ $${#missing[@]} -eq 0 ]; then exit 0; fi
	if [ "$$(id -u)" -eq 0 ]; then
	  echo "installing missing packages: $${missing[*]}"
	  apt-get update
	  DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends "$${missing[@]}"
	else
	  echo "wobble needs these Debian packages, which are not installed:" >&2
	  echo "  sudo apt-get update && sudo apt-get install -y --no-install-recommends $${missing[*]}" >&2
	  exit 1
	fi

fuzz-deps:
	$(MAKE) deps PACKAGES="$(FUZZ_PACKAGES)"

# A new build folder gets Ninja (it schedules the two cores better than make and keeps each
# unit's compile time in .ninja_log); an existing one keeps the generator it was made with.
GENERATOR = $(if $(wildcard $(1)/CMakeCache.txt),,-G Ninja)

configure: deps
	cmake -S . -B $(BUILD) $(call GENERATOR,$(BUILD)) -DCMAKE_BUILD_TYPE=Release -DWOBBLE_SANITIZE=OFF \
	  -DWOBBLE_BUILD_APP=ON -DWOBBLE_BUILD_TESTS=ON -DWOBBLE_BUILD_BENCH=ON

build: configure
	cmake --build $(BUILD) -j $(JOBS)

# The demo needs only the command line, not the tests.
demo-build: configure
	cmake --build $(BUILD) -j $(JOBS) --target wobble_cli

demo: demo-build
	@mkdir -p $(OUT)
	echo
	echo '$$ $(WOBBLE) simulate --object $(DEMO_OBJECT) --modes $(DEMO_MODES) $(DEMO_ARGS) --out $(OUT)/table_drop.csv'
	status=0
	$(WOBBLE) simulate --object $(DEMO_OBJECT) --modes $(DEMO_MODES) $(DEMO_ARGS) --out $(OUT)/table_drop.csv || status=$$?
	# pictures and exports (pipelines/): VTK renders through X, so a virtual one without DISPLAY
	xvfb=""
	if [ -z "$${DISPLAY:-}" ]; then xvfb='xvfb-run -a -s "-screen 0 1280x1024x24"'; fi
	# the main scene: the table jumping off a cliff (Fig. 1.3/4.12: keyframed jump, then simulation);
	# its script ends with `render out/demo ...`: frames, filmstrip, .pvd/.vtp, EXR and charts
	echo
	echo "\$$ $$xvfb" '$(WOBBLE) run $(DEMO_SCRIPT)'
	eval "$$xvfb" '$(WOBBLE) run $(DEMO_SCRIPT)' || status=$$?
	# Witkin & Welch, Fig. 3: the sky hook grabs the pyramid and hangs itself up (issue 7)
	echo "\$$ $$xvfb" '$(WOBBLE) run data/fig3_sky_hook.wob'
	eval "$$xvfb" '$(WOBBLE) run data/fig3_sky_hook.wob' || status=$$?
	# a 3D character with its own mesh (issue 15): the pot revolved from the 2D outline, dropped
	# tilted and spinning; the camera orbits it (frames, filmstrip, charts, .vtp/.pvd, EXR)
	echo "\$$ $$xvfb" '$(WOBBLE) render $(DEMO3D_ARGS) --out $(OUT)/pot3'
	eval "$$xvfb" '$(WOBBLE) render $(DEMO3D_ARGS) --out $(OUT)/pot3' || status=$$?
	echo
	echo "files (the cliff jump, in $(OUT)/):"
	echo "  trajectory  $(OUT)/table_cliff.csv  (t, q, q-dot, energies, control energy, contacts per step)"
	echo "  frames      $(OUT)/frames/frame_NNNN.png  (640x480, 30 fps)"
	echo "  video       $(OUT)/table.mp4  (H.264; plays in a browser: chromium $(OUT)/table.mp4, or ffplay)"
	echo "  filmstrip   $(OUT)/filmstrip.png"
	echo "  ParaView    $(OUT)/vtp/table.pvd  (lattice, mass points, shape per frame; the terrain as its last part)"
	echo "  EXR         $(OUT)/exr/frame_NNNN.exr  (R,G,B,A, depth.Z, forward.u/v motion to the next frame; camera and timeCode in the header), $(OUT)/exr/disp_NNNN.exr  (disp.X, disp.Y)"
	echo "  plots       $(OUT)/energy.png, $(OUT)/condition.png  (numbers in the .csv beside them)"
	echo "  table drop  $(OUT)/table_drop.csv  (the sloped-ground drop, simulated only: README, Pictures and exports)"
	echo "  sky hook    out/fig3/filmstrip.png, out/fig3/frames/, out/fig3/vtp/fig3_sky_hook.pvd  (Witkin & Welch Fig. 3)"
	echo "  3D pot      $(OUT)/pot3/filmstrip.png, $(OUT)/pot3/pot3.mp4, $(OUT)/pot3/frames/, $(OUT)/pot3/vtp/pot3.pvd (deformed mesh, lattice, points), $(OUT)/pot3/exr/"
	echo "  glTF        $(OUT)/pot3/pot3.glb  (mesh, a morph target per mode, the camera; Blender: README, Pictures and exports)"
	echo "  web page    $(OUT)/pot3/web/index.html  (open it in a browser: the pot's run in three.js, orbit, play, time slider)"
	echo "  command     $(WOBBLE)  (see $(WOBBLE) --help, and README.md)"
	exit $$status

# Render tests need a display: ctest runs inside a virtual X server when there is one
# (checked here, after deps may have installed it). A render test skips only without DISPLAY;
# with DISPLAY set and no X server answering it fails.
CTEST_ARGS ?=
test: build
	cd $(BUILD)
	if command -v xvfb-run >/dev/null 2>&1; then
	  xvfb-run -a -s "-screen 0 1280x1024x24" ctest --output-on-failure -j $(JOBS) $(CTEST_ARGS)
	else
	  ctest --output-on-failure -j $(JOBS) $(CTEST_ARGS)
	fi

# The edit-test loop: every test but those labelled `long` (tests/CMakeLists.txt says which, and why)
test-quick:
	$(MAKE) test CTEST_ARGS="-LE long $(CTEST_ARGS)"

# Every test again with AddressSanitizer + UBSan. Debug keeps assertions on; -O1 keeps the
# long physics runs (10^5 steps) to seconds instead of minutes. -g1 (line tables, no variable
# records) still names file and line in every report, and compiles this template-heavy code
# in about 0.7 of -g's time. No display: the render tests skip (the Release run has them).
ASAN_CTEST_ARGS ?=
asan: deps
	cmake -S . -B $(ASAN_BUILD) $(call GENERATOR,$(ASAN_BUILD)) -DWOBBLE_SANITIZE=ON -DCMAKE_BUILD_TYPE=Debug \
	  -DCMAKE_CXX_FLAGS_DEBUG="-O1 -g1" -DWOBBLE_BUILD_BENCH=OFF -DWOBBLE_BUILD_APP=ON -DWOBBLE_BUILD_TESTS=ON
	cmake --build $(ASAN_BUILD) -j $(JOBS)
	cd $(ASAN_BUILD) && env -u DISPLAY ctest --output-on-failure -j $(JOBS) $(ASAN_CTEST_ARGS)

# Every benchmark built, none run: CI builds them so they keep compiling (`make test` does not)
bench-build: configure
	cmake --build $(BUILD) -j $(JOBS) --target benchmarks

bench: configure
	cmake --build $(BUILD) -j $(JOBS) --target wobble_bench wobble_pipelines_bench
	$(BUILD)/bench/wobble_bench
	# rendering and export speed; VTK renders through X
	if [ -n "$${DISPLAY:-}" ]; then $(BUILD)/bench/wobble_pipelines_bench
	else xvfb-run -a -s "-screen 0 1280x1024x24" $(BUILD)/bench/wobble_pipelines_bench; fi

# Fig. 2's triple pendulum, wobble against MuJoCo in one run (issue 18): interleaved
# repetitions, since the machines here are noisy; compare the medians
bench-mujoco: configure
	$(MAKE) deps PACKAGES="$(MUJOCO_PACKAGES)"
	cmake -S . -B $(BUILD) > /dev/null  # finds MuJoCo now that it is installed
	cmake --build $(BUILD) -j $(JOBS) --target mujoco_bench
	$(BUILD)/bench/mujoco_bench --benchmark_min_time=0.3 --benchmark_repetitions=10 \
	  --benchmark_enable_random_interleaving=true --benchmark_report_aggregates_only=true

# Trials over MPI ranks (issue 17): two ranks on this machine, then the model of 100 and 1,000
bench-mpi: configure
	cmake --build $(BUILD) -j $(JOBS) --target mpi_bench
	mkdir -p out
	OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 mpirun -np 2 --oversubscribe \
	  $(BUILD)/bench/mpi_bench --benchmark_out=out/mpi_bench.json
	python3 bench/mpi_scaling_model.py out/mpi_bench.json

# Python against C++ (issue 16): batched trials and the cost of one step() call
bench-python: configure
	cmake --build $(BUILD) -j $(JOBS) --target _wobble synth_bench
	PYTHONPATH=$(BUILD)/python /usr/bin/python3 bench/python_bench.py $(BUILD)

# libFuzzer (fuzz/, issue 14): every target for FUZZ_SECONDS, from the committed corpus and its
# dictionary; new inputs go to $(FUZZ_BUILD)/corpus/TARGET (merge them into fuzz/corpus by hand,
# with -merge=1), crashes to $(FUZZ_BUILD)/artifacts/. Prints the executions of each target.
FUZZ_BUILD   ?= build-fuzz
FUZZ_SECONDS ?= 60
FUZZ_TARGETS ?= object deformation object3 deformation3 targets trajectory_csv script world_step
# the readers take files of any size; scripts and world states are kept short (each input is
# a simulation), and a script that runs longer than 10 s is reported as a hang
FUZZ_FLAGS_object         := -max_len=4096
FUZZ_FLAGS_deformation    := -max_len=4096
FUZZ_FLAGS_object3        := -max_len=4096
FUZZ_FLAGS_deformation3   := -max_len=4096
FUZZ_FLAGS_targets        := -max_len=4096
FUZZ_FLAGS_trajectory_csv := -max_len=8192
FUZZ_FLAGS_script         := -max_len=4096 -timeout=10
FUZZ_FLAGS_world_step     := -max_len=128 -timeout=10
# FUZZ_KEEP_GOING=1: go on past crashes and hangs (libFuzzer's fork mode; each is still saved
# in artifacts/), for targets with open findings; executions then come from the progress lines
FUZZ_KEEP_GOING ?=
fuzz: deps fuzz-deps
	CC=clang CXX=clang++ cmake -S . -B $(FUZZ_BUILD) -DWOBBLE_FUZZ=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	  -DWOBBLE_BUILD_TESTS=OFF -DWOBBLE_BUILD_PIPELINES=OFF -DWOBBLE_BUILD_APP=OFF -DWOBBLE_BUILD_BENCH=OFF
	cmake --build $(FUZZ_BUILD) -j $(JOBS) --target $(addprefix fuzz_,$(FUZZ_TARGETS))
	mkdir -p $(FUZZ_BUILD)/artifacts
	status=0
	summary=""
	for t in $(FUZZ_TARGETS); do
	  mkdir -p $(FUZZ_BUILD)/corpus/$$t
	  log=$(FUZZ_BUILD)/fuzz_$$t.log
	  case $$t in
	    object) flags="$(FUZZ_FLAGS_object)" ;; deformation) flags="$(FUZZ_FLAGS_deformation)" ;;
	    object3) flags="$(FUZZ_FLAGS_object3)" ;; deformation3) flags="$(FUZZ_FLAGS_deformation3)" ;;
	    targets) flags="$(FUZZ_FLAGS_targets)" ;; trajectory_csv) flags="$(FUZZ_FLAGS_trajectory_csv)" ;;
	    script) flags="$(FUZZ_FLAGS_script)" ;; world_step) flags="$(FUZZ_FLAGS_world_step)" ;; *) flags="" ;;
	  esac
	  echo "== fuzz_$$t for $(FUZZ_SECONDS) s (log: $$log)"
	  # world_step reads binary values: no dictionary
	  if [ -f fuzz/dict/$$t.dict ]; then flags="$$flags -dict=$(CURDIR)/fuzz/dict/$$t.dict"; fi
	  if [ -n "$(FUZZ_KEEP_GOING)" ]; then flags="$$flags -fork=1 -ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1"; fi
	  rc=0
	  # absolute paths: fuzz_script changes its working directory, and libFuzzer reads the
	  # corpus files after the first input ran
	  $(FUZZ_BUILD)/fuzz/fuzz_$$t -max_total_time=$(FUZZ_SECONDS) -print_final_stats=1 $$flags \
	    -artifact_prefix=$(abspath $(FUZZ_BUILD))/artifacts/$$t- \
	    $(abspath $(FUZZ_BUILD))/corpus/$$t $(CURDIR)/fuzz/corpus/$$t > $$log 2>&1 || rc=$$?
	  execs=$$(sed -n 's/^stat::number_of_executed_units: *//p' $$log | tail -1)
	  rate=$$(sed -n 's/^stat::average_exec_per_sec: *//p' $$log | tail -1)
	  # no final stats after a crash or in fork mode: the last progress line's count
	  if [ -z "$$execs" ]; then execs=$$(sed -n 's/^#\([0-9][0-9]*\).*/\1/p' $$log | tail -1); fi
	  line="fuzz_$$t: $${execs:-?} executions, $${rate:-?} exec/s"
	  if [ $$rc -ne 0 ]; then line="$$line, FAILED (exit $$rc; see $$log and $(FUZZ_BUILD)/artifacts/)"; status=1; fi
	  echo "$$line"
	  summary="$$summary$$line"$$'\n'
	done
	echo
	printf '%s' "$$summary"
	exit $$status

clean:
	rm -rf $(BUILD) $(ASAN_BUILD) $(FUZZ_BUILD) out
