# The two commands of the README, plus the targets they are made of.
#   make demo    install what is missing, build, run the main job on the built-in tasks
#   make check   install what is missing, build, run every test (ctest)
# Other targets: deps, build, check-slow, check-slurm, install, sanitize, fuzz, man, bench, clean.

BUILD    ?= build
JOBS     ?= $(shell nproc)
CMAKE_FLAGS ?=
PREFIX   ?= /usr/local
FUZZ_SECONDS ?= 600
APT_PACKAGES := $(shell sed -e 's/\#.*//' debian-packages.txt)
TOOLS := $(basename $(notdir $(wildcard tools/*.cpp)))

.PHONY: all deps build check check-slow check-slurm demo install sanitize fuzz man bench clean

all: build

# Installs the Debian packages of debian-packages.txt that are not installed yet.
deps:
	@missing=$$(for p in $(APT_PACKAGES); do dpkg-query -W -f='$${Status}\n' $$p 2>/dev/null | grep -q '^install ok installed' || echo $$p; done); \
	if [ -n "$$missing" ]; then \
	  echo "installing Debian packages:" $$missing; \
	  SUDO=$$( [ "$$(id -u)" = 0 ] || echo sudo ); \
	  $$SUDO apt-get update -q && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -q --no-install-recommends $$missing; \
	fi

$(BUILD)/CMakeCache.txt: | deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS)

build: deps $(BUILD)/CMakeCache.txt
	cmake --build $(BUILD) -j $(JOBS)

# Every test except those labelled slow (see check-slow) or slurm (see check-slurm).
check: build
	ctest --test-dir $(BUILD) --output-on-failure -j $(JOBS) -LE 'slow|slurm'

check-slow: build
	ctest --test-dir $(BUILD) --output-on-failure -j $(JOBS) -L slow

# The cluster tests: a throwaway single-node Slurm cluster (Debian's slurm-wlm and munge, from
# debian-packages-slurm.txt) runs an experiment grid and a split run (tests/slurm/).
check-slurm: build
	$(MAKE) deps APT_PACKAGES="$$(sed -e 's/#.*//' debian-packages-slurm.txt | tr '\n' ' ')"
	ctest --test-dir $(BUILD) --output-on-failure -L slurm

demo: build
	PATH="$(CURDIR)/$(BUILD)/tools:$$PATH" bash examples/demo.sh

install: build
	cmake --install $(BUILD) --prefix $(PREFIX)

# AddressSanitizer + UndefinedBehaviorSanitizer build running the same tests.
sanitize: deps
	cmake -S . -B $(BUILD)-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DQTE_SANITIZE=ON $(CMAKE_FLAGS)
	cmake --build $(BUILD)-asan -j $(JOBS)
	ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
	  ctest --test-dir $(BUILD)-asan --output-on-failure -j $(JOBS) -LE 'slow|slurm'

# libFuzzer for FUZZ_SECONDS of CPU time per target (clang from debian-packages.txt): the stream
# decoder, each record type's readers, then the camera files' readers (.pcd; PNG and joint CSV)
# (tests/fuzz/fuzz_<target>.cpp, seeds in tests/fuzz/corpus/<target>/). A finding is written to
# tests/fuzz/findings/ and fails the target.
FUZZ_TARGETS ?= stream_reader obs action trajectory transition checkpoint pcd camera_recordings driver_answer
fuzz: deps
	cmake -S . -B $(BUILD)-fuzz -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
	  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DQTE_FUZZ=ON -DQTE_TESTS=ON $(CMAKE_FLAGS)
	cmake --build $(BUILD)-fuzz -j $(JOBS) --target $(addprefix fuzz_,$(FUZZ_TARGETS))
	mkdir -p tests/fuzz/findings
	for t in $(FUZZ_TARGETS); do \
	  mkdir -p $(BUILD)-fuzz/corpus/$$t; \
	  tests/fuzz/run_for_cpu.sh $(FUZZ_SECONDS) $(BUILD)-fuzz/tests/fuzz/fuzz_$$t -rss_limit_mb=4096 \
	    -artifact_prefix=tests/fuzz/findings/$$t- -print_final_stats=1 \
	    $(BUILD)-fuzz/corpus/$$t tests/fuzz/corpus/$$t || exit 1; \
	done

# Regenerates man/*.1 from the programs' own --help-man (a test checks they agree).
man: build
	for t in $(TOOLS); do $(BUILD)/tools/$$t --help-man > man/$$t.1; done

bench: build
	@for b in $(BUILD)/tests/bench/bench_*; do echo "== $$(basename $$b)"; $$b; done

clean:
	rm -rf $(BUILD) $(BUILD)-asan $(BUILD)-fuzz
