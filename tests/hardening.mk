# Hardening targets (included by the Makefile): fuzzing, determinism, the
# arm64 cross build run under qemu, and the freestanding Cortex-M4 build.
#
#   make fuzz                 every libFuzzer target in tests/fuzz/ for
#                             FUZZ_SECONDS each (default 60), clang + ASan + UBSan
#   make fuzz-replay          the same targets built with $(CC) + ASan/UBSan and
#                             run once over their seeds (no clang needed)
#   make check-determinism    `polarlux gen` bytes, `polarlux info` output
#                             (minus the timing line) and render/heatmap
#                             PNG/PFM bytes equal across runs
#   make check-arm64          cross-compiles for aarch64 and runs the whole test
#                             suite under qemu-user, then compares gen/info output
#                             with the host's
#   make check-freestanding   builds src/*.c with -ffreestanding for a Cortex-M4
#                             (arm-none-eabi), checks the symbols it needs and
#                             prints its code size
#   make hardening-deps       installs the toolchains these need (Debian, as root)
#
# Adding a fuzz target (e.g. the points-file readers): drop
# tests/fuzz/fuzz_NAME.c defining LLVMFuzzerTestOneInput, and optionally set
# FUZZ_SEEDS_fuzz_NAME below to its seed folders (default: fixtures/).
# Every target is also run by fuzz-replay over its seeds. A crash found is
# fixed, then its input goes to tests/corpus/ with its exact outcome as a row
# of tests/unit/test_corpus.c (and so becomes a seed too).

.PHONY: fuzz fuzz-build fuzz-replay check-determinism check-arm64 check-arm64-build \
        check-freestanding hardening-deps

# ---- fuzzing -------------------------------------------------------------------
FUZZ_SECONDS ?= 60
FUZZ_CC      ?= clang
FUZZ_BUILD    = build/fuzz
FUZZ_SRC      = $(wildcard tests/fuzz/fuzz_*.c)
FUZZ_NAMES    = $(FUZZ_SRC:tests/fuzz/%.c=%)
FUZZ_SAN      = -fsanitize=address,undefined -fno-sanitize-recover=all
# Seed folders per target (fixtures/ when not set). New inputs found by a run
# go to build/fuzz/corpus/NAME, crashes to build/fuzz/crash-NAME-*.
FUZZ_SEEDS_fuzz_geojson = fixtures tests/corpus
FUZZ_SEEDS_fuzz_scene   = fixtures tests/corpus
FUZZ_SEEDS_fuzz_jsoncheck = fixtures tests/corpus
FUZZ_SEEDS_fuzz_bake    = tests/corpus
FUZZ_SEEDS_fuzz_ies     = fixtures/photometry tests/fuzz/seeds-photometry
FUZZ_SEEDS_fuzz_ldt     = fixtures/photometry tests/fuzz/seeds-photometry
FUZZ_OPTS ?= -timeout=20 -rss_limit_mb=4096 -max_len=65536 -print_final_stats=1

fuzz-build:
	$(MAKE) BUILD=$(FUZZ_BUILD) CC=$(FUZZ_CC) OPT="-O1 -g -fno-omit-frame-pointer" \
	  EXTRA_CFLAGS="-fsanitize=fuzzer-no-link $(FUZZ_SAN) -DPLX_DEBUG" $(FUZZ_BUILD)/libpolarlux-internal.a $(FUZZ_BUILD)/libpolarlux-port-internal.a
	@for n in $(FUZZ_NAMES); do \
	  echo "$(FUZZ_CC) ... tests/fuzz/$$n.c -o $(FUZZ_BUILD)/$$n"; \
	  $(FUZZ_CC) $(CPPFLAGS) $(POSIX) $(WARN) $(FPFLAGS) -O1 -g -fsanitize=fuzzer $(FUZZ_SAN) \
	    tests/fuzz/$$n.c -o $(FUZZ_BUILD)/$$n $(FUZZ_BUILD)/libpolarlux-port-internal.a $(FUZZ_BUILD)/libpolarlux-internal.a $(LIBS) || exit 1; \
	done

fuzz_seeds = $(or $(FUZZ_SEEDS_$(1)),fixtures)

fuzz: fuzz-build
	@$(foreach n,$(FUZZ_NAMES),sh tests/fuzz/run.sh $(FUZZ_BUILD) $(n) $(FUZZ_SECONDS) \
	  "$(FUZZ_OPTS)" $(call fuzz_seeds,$(n)) && ) \
	echo "fuzz: $(words $(FUZZ_NAMES)) targets, $(FUZZ_SECONDS) s each, no crash"

# The fuzz targets without libFuzzer: a small driver feeds them every seed
# file once, built with the default compiler and the sanitizers.
REPLAY_BUILD = build/fuzz-replay
fuzz-replay:
	$(MAKE) BUILD=$(REPLAY_BUILD) OPT="-O1 -g -fno-omit-frame-pointer" \
	  EXTRA_CFLAGS="$(FUZZ_SAN) -DPLX_DEBUG" $(REPLAY_BUILD)/libpolarlux-internal.a $(REPLAY_BUILD)/libpolarlux-port-internal.a
	@for n in $(FUZZ_NAMES); do \
	  $(CC) $(CPPFLAGS) $(POSIX) $(WARN) $(FPFLAGS) -O1 -g $(FUZZ_SAN) tests/fuzz/$$n.c \
	    tests/fuzz/replay_main.c -o $(REPLAY_BUILD)/$$n $(REPLAY_BUILD)/libpolarlux-port-internal.a $(REPLAY_BUILD)/libpolarlux-internal.a $(LIBS) || exit 1; \
	done
	@$(foreach n,$(FUZZ_NAMES),$(REPLAY_BUILD)/$(n) $(call fuzz_seeds,$(n)) && ) \
	echo "fuzz-replay: $(words $(FUZZ_NAMES)) targets clean"

# ---- determinism ----------------------------------------------------------------
# The same input and options give the same bytes: gen twice (stdout and -o),
# info twice with the heap poisoned differently; only timings ("12.34 ms",
# the load time and build times) may differ and are blanked.
UNTIMED = sed -E 's/[0-9]+(\.[0-9]+)? ms/_ ms/g'
check-determinism: all
	@set -e; t=$$(mktemp -d); trap 'rm -rf "$$t"' EXIT; n=0; \
	for style in grid eixample oldtown; do for seed in 1 42; do \
	  $(BIN) gen $$style 7 5 --seed $$seed >$$t/a; \
	  MALLOC_PERTURB_=85 $(BIN) gen $$style 7 5 --seed $$seed -o $$t/b; \
	  cmp $$t/a $$t/b || { echo "determinism: gen $$style seed $$seed differs"; exit 1; }; \
	  n=$$((n + 1)); \
	done; done; \
	for f in fixtures/*.geojson $$t/a; do \
	  $(BIN) info "$$f" 2>&1 | $(UNTIMED) >$$t/i1; \
	  MALLOC_PERTURB_=170 $(BIN) info "$$f" 2>&1 | $(UNTIMED) >$$t/i2; \
	  cmp $$t/i1 $$t/i2 || { echo "determinism: info $$f differs"; diff $$t/i1 $$t/i2 | head; exit 1; }; \
	  n=$$((n + 1)); \
	done; \
	for view in street aerial; do \
	  $(BIN) render -q fixtures/eixample-4x4.geojson --view $$view --size 160x120 --frames 4 --photons 8000 \
	    -o $$t/r1.png --pfm $$t/r1.pfm >/dev/null; \
	  MALLOC_PERTURB_=85 $(BIN) render -q fixtures/eixample-4x4.geojson --view $$view --size 160x120 --frames 4 \
	    --photons 8000 -o $$t/r2.png --pfm $$t/r2.pfm >/dev/null; \
	  cmp $$t/r1.png $$t/r2.png && cmp $$t/r1.pfm $$t/r2.pfm || { echo "determinism: render $$view differs"; exit 1; }; \
	  n=$$((n + 2)); \
	done; \
	$(BIN) heatmap -q fixtures/tiny.geojson --res 1 -o $$t/h1.png >/dev/null; \
	MALLOC_PERTURB_=85 $(BIN) heatmap -q fixtures/tiny.geojson --res 1 -o $$t/h2.png >/dev/null; \
	cmp $$t/h1.png $$t/h2.png || { echo "determinism: heatmap differs"; exit 1; }; \
	n=$$((n + 1)); \
	echo "determinism: $$n passed, 0 failed"

# ---- arm64 under qemu-user ---------------------------------------------------------
ARM64_CC    ?= aarch64-linux-gnu-gcc
ARM64_QEMU  ?= qemu-aarch64
ARM64_BUILD  = build/arm64
ARM64_RUN    = $(ARM64_BUILD)/qemu
ARM64_TESTS  = $(TEST_SRC:tests/unit/%.c=$(ARM64_BUILD)/tests/%)

check-arm64-build:
	@command -v $(ARM64_CC) >/dev/null && command -v $(ARM64_QEMU) >/dev/null || \
	  { echo "check-arm64: needs $(ARM64_CC) and $(ARM64_QEMU) (make hardening-deps)" >&2; exit 1; }
	$(MAKE) BUILD=$(ARM64_BUILD) CC=$(ARM64_CC) $(ARM64_BUILD)/polarlux $(ARM64_TESTS) $(ARM64_BUILD)/tests/tiff_probe

# Each binary gets a wrapper script running it under qemu, so the ordinary
# test runner (and the cli tests) run the arm64 programs unchanged.
check-arm64: check-arm64-build all
	@rm -rf $(ARM64_RUN); mkdir -p $(ARM64_RUN)/tests
	@for b in $(ARM64_BUILD)/polarlux $(ARM64_TESTS) $(ARM64_BUILD)/tests/tiff_probe; do \
	  w=$(ARM64_RUN)/$${b#$(ARM64_BUILD)/}; \
	  printf '#!/bin/sh\nexec %s %s "$$@"\n' "$(ARM64_QEMU)" "$(CURDIR)/$$b" >$$w; chmod +x $$w; \
	done
	@file $(ARM64_BUILD)/polarlux | grep -q 'ARM aarch64' || { echo "check-arm64: not an aarch64 binary"; exit 1; }
	@# every test runs, with the shorter random loops of the quick mode (qemu is
	@# about 10x slower than the host; the host runs the full loops)
	@PLX_TEST_QUICK=1 PLX_TEST_SKIP_SLOW= PLX_NO_SHIM='an x86 shim cannot reach a program under qemu' \
	  PLX_NO_FORK_THREADS='qemu-user aborts when a child of a threaded process starts threads' \
	  sh tests/run_tests.sh $(ARM64_RUN) $(ARM64_TESTS:$(ARM64_BUILD)/%=$(ARM64_RUN)/%)
	@set -e; t=$$(mktemp -d); trap 'rm -rf "$$t"' EXIT; n=0; \
	for style in grid eixample oldtown; do \
	  $(BIN) gen $$style 6 4 --seed 9 >$$t/x; $(ARM64_RUN)/polarlux gen $$style 6 4 --seed 9 >$$t/a; \
	  cmp $$t/x $$t/a || { echo "arm64: gen $$style differs from the host"; exit 1; }; n=$$((n + 1)); \
	done; \
	for f in fixtures/*.geojson; do \
	  $(BIN) info "$$f" 2>&1 | $(UNTIMED) >$$t/x; \
	  $(ARM64_RUN)/polarlux info "$$f" 2>&1 | $(UNTIMED) >$$t/a; \
	  cmp $$t/x $$t/a || { echo "arm64: info $$f differs from the host"; diff $$t/x $$t/a | head; exit 1; }; \
	  n=$$((n + 1)); \
	done; echo "arm64 same output as host: $$n passed, 0 failed"

# ---- freestanding Cortex-M4 --------------------------------------------------------
# The core is compiled with -ffreestanding for arm-none-eabi against the
# toolchain's own headers (no cJSON.h: the core reads JSON itself) and linked
# into one relocatable object: the size is the core's own code. Every symbol
# left undefined must be the compiler runtime's (__aeabi_*) or one of the C
# library functions the core may use (string.h, math.h, qsort, strtod).
FS_CC     ?= arm-none-eabi-gcc
FS_BUILD   = build/freestanding
FS_FLAGS   = -ffreestanding -mthumb -mcpu=cortex-m4 -Os -ffunction-sections -fdata-sections
FS_OBJ     = $(CORE_SRC:src/%.c=$(FS_BUILD)/%.o)
# string.h, qsort, strtod (the scene's numbers, read as cJSON read them) and
# every C99 math.h function (double and float)
FS_ALLOWED = memcpy memmove memset memcmp memchr strlen strcmp strncmp strchr strrchr strstr qsort \
             acos asin atan atan2 cos sin tan acosh asinh atanh cosh sinh tanh exp exp2 \
             expm1 frexp ldexp log log10 log1p log2 logb modf scalbn cbrt fabs hypot \
             pow sqrt erf erfc lgamma tgamma ceil floor nearbyint rint lrint llrint \
             round lround llround trunc fmod remainder remquo copysign nan nextafter \
             fdim fmax fmin fma acosf asinf atanf atan2f cosf sinf tanf acoshf asinhf \
             atanhf coshf sinhf tanhf expf exp2f expm1f frexpf ldexpf logf log10f \
             log1pf log2f logbf modff scalbnf cbrtf fabsf hypotf powf sqrtf erff erfcf \
             lgammaf tgammaf ceilf floorf nearbyintf rintf lrintf llrintf roundf \
             lroundf llroundf truncf fmodf remainderf remquof copysignf nanf nextafterf \
             fdimf fmaxf fminf fmaf \
             strtod

$(FS_BUILD)/%.o: src/%.c
	@mkdir -p $(@D)
	$(FS_CC) -Iinclude -Isrc $(WARN) $(FPFLAGS) $(FS_FLAGS) -c $< -o $@

check-freestanding:
	@command -v $(FS_CC) >/dev/null || { echo "check-freestanding: needs $(FS_CC) (make hardening-deps)" >&2; exit 1; }
	@$(MAKE) --no-print-directory $(FS_OBJ)
	$(FS_CC:gcc=ld) -r -o $(FS_BUILD)/polarlux-core.o $(FS_OBJ)
	@bad=$$($(FS_CC:gcc=nm) -u $(FS_BUILD)/polarlux-core.o | awk '{print $$2}' | \
	  grep -vE '^__aeabi_[a-z0-9_]+$$' | \
	  grep -vxF "$$(printf '%s\n' $(FS_ALLOWED))" || true); \
	if [ -n "$$bad" ]; then echo "check-freestanding: the core needs symbols a bare-metal target may lack:"; \
	  echo "$$bad"; exit 1; fi
	@echo "check-freestanding: $(words $(FS_OBJ)) files, undefined symbols:" \
	  $$($(FS_CC:gcc=nm) -u $(FS_BUILD)/polarlux-core.o | awk '{print $$2}' | grep -v '^__aeabi' | tr '\n' ' ')
	@$(FS_CC:gcc=size) $(FS_OBJ) $(FS_BUILD)/polarlux-core.o

# ---- toolchains ----------------------------------------------------------------------
HARDENING_PACKAGES = clang libclang-rt-14-dev valgrind file gcc-aarch64-linux-gnu libc6-dev-arm64-cross qemu-user \
                     libcjson-dev:arm64 libcmocka-dev:arm64 libpng-dev:arm64 libsqlite3-dev:arm64 libtiff-dev:arm64 libgeotiff-dev:arm64 \
                     gcc-arm-none-eabi libnewlib-arm-none-eabi

hardening-deps:
	@if [ "$$(id -u)" != 0 ]; then echo "run as root: dpkg --add-architecture arm64;" \
	  "apt-get update; apt-get install $(HARDENING_PACKAGES)" >&2; exit 1; fi
	dpkg --print-foreign-architectures | grep -qx arm64 || dpkg --add-architecture arm64
	apt-get update -qq
	DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $(HARDENING_PACKAGES) >/dev/null
