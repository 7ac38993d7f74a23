# polarlux — build, test and install. See README.md.
#
#   make            the core library (build/libpolarlux.a, libpolarlux.so), the
#                   POSIX/PNG port library (build/libpolarlux-port.a) and build/polarlux
#   make demo       build and run the main job on the bundled fixtures
#   make check      unit + command-line tests, quick (long loops shortened)
#   make check-full the same with the full loops and bounds (a few minutes)
#   make asan       the same tests under AddressSanitizer + UBSan, with the
#                   core's invariant checks (PLX_DEBUG, src/base/plx_assert.h)
#   make valgrind   the unit tests under valgrind memcheck
#   make bench      benchmarks (tests/bench)
#   make check-identical BASE=rev   outputs byte-identical to revision rev
#   make deps       install missing Debian packages (apt-get when root); plain
#                   make only checks them and names what is missing
#   make man        regenerate man/polarlux.1 from the --help texts
#   make install PREFIX=/usr/local
#   make clean

CC      ?= cc
PREFIX  ?= /usr/local
BUILD   ?= build
JOBS    ?= $(shell getconf _NPROCESSORS_ONLN 2>/dev/null || echo 2)
OPT     ?= -O2 -g
WARN     = -std=c99 -Wall -Wextra -Werror -pedantic -Wshadow -Wpointer-arith \
           -Wstrict-prototypes -Wundef
# Exact predicates need IEEE double arithmetic without fused multiply-add.
FPFLAGS  = -ffp-contract=off
CPPFLAGS = -Iinclude -Isrc -Iport
CFLAGS_ALL = $(WARN) $(FPFLAGS) $(OPT) -fPIC -MMD -MP $(EXTRA_CFLAGS)
POSIX    = -D_POSIX_C_SOURCE=200809L
# The core needs libm only (it reads JSON itself, without cJSON); the port
# (port/posix, port/png) adds libpng, zlib (the animated PNG's CRCs, with
# libpng's own zlib) and pthreads. The command and the tests link both with
# $(LIBS), which adds cJSON: they still parse JSON with it.
CORE_LIBS = -lm
PORT_LIBS = -lpng -lz -lpthread
LIBS     = -lcjson -lpng -lz -lm -lpthread
# The command alone also links SQLite (polarlux tiles to MBTiles).
CLI_LIBS = -lsqlite3

CORE_DIRS = base scene polar light photon render api
CORE_SRC = $(foreach d,$(CORE_DIRS),$(wildcard src/$(d)/*.c))
PORT_SRC = $(wildcard port/posix/*.c) $(wildcard port/png/*.c)
CLI_SRC  = $(wildcard src/cli/*.c)
REF_SRC  = $(wildcard tests/ref/*.c)
TEST_SRC = $(wildcard tests/unit/test_*.c)
BENCH_SRC = $(wildcard tests/bench/bench_*.c)

CORE_OBJ = $(CORE_SRC:%.c=$(BUILD)/%.o)
PORT_OBJ = $(PORT_SRC:%.c=$(BUILD)/%.o)
CLI_OBJ  = $(CLI_SRC:%.c=$(BUILD)/%.o)
REF_OBJ  = $(REF_SRC:%.c=$(BUILD)/%.o)
TESTS    = $(TEST_SRC:tests/unit/%.c=$(BUILD)/tests/%)
BENCHES  = $(BENCH_SRC:tests/bench/%.c=$(BUILD)/bench/%)

VERSION = $(shell sed -n 's/^\#define PLX_VERSION_STRING "\(.*\)"/\1/p' include/polarlux.h)
VERSION_MAJOR = $(firstword $(subst ., ,$(VERSION)))

# libpolarlux.so -> libpolarlux.so.MAJOR (the SONAME) -> libpolarlux.so.VERSION
LIB_A  = $(BUILD)/libpolarlux.a
SONAME = libpolarlux.so.$(VERSION_MAJOR)
LIB_SO_REAL = $(BUILD)/libpolarlux.so.$(VERSION)
LIB_SO = $(BUILD)/libpolarlux.so
PORT_A = $(BUILD)/libpolarlux-port.a
# The archives our own programs link (the command, tests, benches, fuzz
# targets): every object as compiled, internals reachable. LIB_A and PORT_A,
# the ones embedders link, hold one object each whose only global symbols
# are plx_* (an application's own arena_alloc or camera_setup clashed).
LIB_INT  = $(BUILD)/libpolarlux-internal.a
PORT_INT = $(BUILD)/libpolarlux-port-internal.a
# the target's objcopy: aarch64-linux-gnu-gcc's is aarch64-linux-gnu-objcopy
# (the host's cannot read its objects)
OBJCOPY ?= $(if $(filter %gcc,$(CC)),$(patsubst %gcc,%objcopy,$(CC)),objcopy)
BIN    = $(BUILD)/polarlux
DEB_PACKAGES = libcjson-dev libcmocka-dev libpng-dev zlib1g-dev pkg-config python3-numpy python3-pytest libsqlite3-dev \
               libosmesa6-dev

.SECONDARY:
.PHONY: all deps deps-check check-no-install man check-man demo check check-full check-build unit cli-test asan \
        valgrind bench install clean check-core-headers check-identical check-lib-split check-examples check-python \
        check-layers check-hostile-valgrind check-install

all: $(LIB_A) $(LIB_SO) $(PORT_A) $(LIB_INT) $(PORT_INT) $(BIN)

# ---- dependencies ------------------------------------------------------------
# Plain `make` never installs anything: it checks that the build's Debian
# packages are there (when dpkg is) and stops naming the missing ones.
# `make deps` installs every package of DEB_PACKAGES (with apt-get, as root)
# and says which. The Python packages are needed by `make check` only.
BUILD_PACKAGES = libcjson-dev libcmocka-dev libpng-dev zlib1g-dev pkg-config libsqlite3-dev
missing_packages = for p in $(1); do \
	  dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q "ok installed" || missing="$$missing $$p"; \
	done

deps-check:
	@command -v dpkg-query >/dev/null || exit 0; missing=""; \
	$(call missing_packages,$(BUILD_PACKAGES)); \
	if [ -n "$$missing" ]; then \
	  echo "make: missing Debian packages:$$missing; 'make deps' installs them (as root)," \
	    "or run: apt-get install$$missing" >&2; exit 1; fi

# The rule above, checked: building runs no package manager.
check-no-install:
	@if $(MAKE) --no-print-directory -n -B all 2>/dev/null | grep -q 'apt-get update'; then \
	  echo "check-no-install: plain make would run apt-get"; exit 1; fi

deps:
	@missing=""; $(call missing_packages,$(DEB_PACKAGES)); \
	if [ -z "$$missing" ]; then echo "make deps: all installed: $(DEB_PACKAGES)"; exit 0; fi; \
	if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null; then \
	  echo "make deps: installing$$missing (apt-get install)"; \
	  (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq$$missing) >/dev/null || \
	  { echo "make deps: apt-get failed; run: apt-get install$$missing" >&2; exit 1; }; \
	  echo "make deps: installed$$missing"; \
	else \
	  echo "make deps: missing packages; run as root: apt-get install$$missing" >&2; exit 1; \
	fi

# ---- objects -----------------------------------------------------------------
$(BUILD)/src/%.o: src/%.c | deps-check
	@mkdir -p $(@D)
	$(CC) $(CPPFLAGS) $(CFLAGS_ALL) -c $< -o $@

$(BUILD)/src/cli/%.o: src/cli/%.c | deps-check
	@mkdir -p $(@D)
	$(CC) $(CPPFLAGS) $(POSIX) $(CFLAGS_ALL) -c $< -o $@

$(BUILD)/port/%.o: port/%.c | deps-check
	@mkdir -p $(@D)
	$(CC) $(CPPFLAGS) $(POSIX) $(CFLAGS_ALL) -c $< -o $@

$(BUILD)/tests/%.o: tests/%.c | deps-check
	@mkdir -p $(@D)
	$(CC) $(CPPFLAGS) -Itests/ref $(POSIX) $(CFLAGS_ALL) -c $< -o $@

$(LIB_INT): $(CORE_OBJ)
	@rm -f $@
	ar rcs $@ $^

$(PORT_INT): $(PORT_OBJ)
	@rm -f $@
	ar rcs $@ $^

# One relocatable object of all the archive's objects, every global symbol
# but plx_* made local (references between the objects are resolved by then).
define public_archive
	@rm -f $@ $@.o
	$(CC) -r -nostdlib -o $@.o $^
	$(OBJCOPY) --wildcard --keep-global-symbol='plx_*' $@.o
	ar rcs $@ $@.o
	@rm -f $@.o
endef

$(LIB_A): $(CORE_OBJ)
	$(public_archive)

$(PORT_A): $(PORT_OBJ)
	$(public_archive)

$(LIB_SO_REAL): $(CORE_OBJ) src/polarlux.map
	$(CC) -shared -Wl,-soname,$(SONAME) -Wl,--version-script=src/polarlux.map -o $@ $(CORE_OBJ) $(CORE_LIBS)

$(LIB_SO): $(LIB_SO_REAL)
	ln -sf $(notdir $(LIB_SO_REAL)) $(BUILD)/$(SONAME)
	ln -sf $(SONAME) $@

$(BIN): $(CLI_OBJ) $(PORT_INT) $(LIB_INT)
	$(CC) $(CFLAGS_ALL) -o $@ $(CLI_OBJ) $(PORT_INT) $(LIB_INT) $(LIBS) $(CLI_LIBS)

$(BUILD)/tests/test_%: $(BUILD)/tests/unit/test_%.o $(REF_OBJ) $(PORT_INT) $(LIB_INT)
	$(CC) $(CFLAGS_ALL) -o $@ $< $(REF_OBJ) $(PORT_INT) $(LIB_INT) -lcmocka $(LIBS)

# Tests and benches of the command's network and tile code link those objects.
CLI_TEST_OBJ = $(addprefix $(BUILD)/src/cli/,network.o net_scores.o route_io.o geo_out.o tiles.o mbtiles.o cmd_heatmap.o \
               canvas.o common.o cmd_network.o cmd_tiles.o cmd_route.o lamp_layer.o bigmem.o options.o points.o \
               twin_engines.o)
CLI_TESTS = $(BUILD)/tests/test_network $(BUILD)/tests/test_tiles $(BUILD)/bench/bench_network
$(CLI_TESTS): $(CLI_TEST_OBJ)
$(BUILD)/tests/test_network $(BUILD)/tests/test_tiles: $(BUILD)/tests/test_%: $(BUILD)/tests/unit/test_%.o $(REF_OBJ) $(PORT_INT) $(LIB_INT)
	$(CC) $(CFLAGS_ALL) -o $@ $< $(CLI_TEST_OBJ) $(REF_OBJ) $(PORT_INT) $(LIB_INT) -lcmocka $(LIBS) $(CLI_LIBS)
$(BUILD)/bench/bench_network: $(BUILD)/tests/bench/bench_network.o $(REF_OBJ) $(PORT_INT) $(LIB_INT)
	@mkdir -p $(@D)
	$(CC) $(CFLAGS_ALL) -o $@ $< $(CLI_TEST_OBJ) $(REF_OBJ) $(PORT_INT) $(LIB_INT) $(LIBS) $(CLI_LIBS)

$(BUILD)/bench/bench_%: $(BUILD)/tests/bench/bench_%.o $(REF_OBJ) $(PORT_INT) $(LIB_INT)
	@mkdir -p $(@D)
	$(CC) $(CFLAGS_ALL) -o $@ $< $(REF_OBJ) $(PORT_INT) $(LIB_INT) $(LIBS)

-include port/osmesa/osmesa.mk

# ---- GeoTIFF maps (libtiff + libgeotiff): linked to the command only -------------
DEB_PACKAGES += libtiff-dev libgeotiff-dev
GIS_CFLAGS = -I/usr/include/geotiff
GIS_LIBS   = -lgeotiff -ltiff
$(BUILD)/src/cli/geotiff.o: CPPFLAGS += $(GIS_CFLAGS)
# the command opens libgeotiff (and through it libtiff) with dlopen when it
# writes a GeoTIFF (src/cli/geotiff.c says why), so it links only -ldl
$(BIN): LIBS += -ldl
# tests/tools/tiff_probe reads a GeoTIFF back for tests/cli/gis.sh
GIS_TOOLS = $(BUILD)/tests/tiff_probe
$(BUILD)/tests/tiff_probe: tests/tools/tiff_probe.c | deps
	@mkdir -p $(@D)
	$(CC) $(CPPFLAGS) $(GIS_CFLAGS) $(POSIX) $(CFLAGS_ALL) -o $@ $< $(GIS_LIBS) -lm
check-build: $(GIS_TOOLS)
# the network and tile tests link cmd_heatmap.o, which writes GeoTIFFs
CLI_TEST_OBJ += $(BUILD)/src/cli/geotiff.o
$(CLI_TESTS): $(BUILD)/src/cli/geotiff.o
CLI_LIBS += -ldl
-include $(shell find $(BUILD) -name '*.d' 2>/dev/null)

# ---- the main job -------------------------------------------------------------
# The README's two commands set up what is missing through make deps (which
# says what it installs); plain make only builds and names what is missing.
demo:
	@$(MAKE) --no-print-directory deps
	@$(MAKE) --no-print-directory -j$(JOBS) all
	@sh tests/demo.sh $(BIN)

# ---- tests --------------------------------------------------------------------
# make check: the quick suite (long random loops shortened by
# PLX_TEST_QUICK; well under a minute), built and run in parallel.
# make check-full: the full loops and bounds the issues ask for (12,000
# visibility points against the brute force, photon accuracy at the default
# photon count, the 10^6-vertex ring built in 256 MiB, ...); a few minutes.
# CI runs both.
# SKIP_SLOW=1 (plain make check) also leaves out the hostile corpus, the
# slowest unit tests (tests/unit/slow.h) and two command-line blocks, so it
# stays within a minute; make asan runs them under the sanitizers.
SKIP_SLOW ?= 1
check: check-build
	@PLX_TEST_QUICK=1 PLX_TEST_SKIP_SLOW=$(SKIP_SLOW) sh tests/run_tests.sh $(BUILD) $(TESTS)
	@$(MAKE) --no-print-directory check-examples check-python check-install

# check-full also builds every benchmark (not run), so one that falls behind
# the code fails here rather than in make bench
check-full: check-build $(BENCHES)
	@PLX_POLAR_RING_BIG=1 PLX_TEST_SKIP_SLOW= sh tests/run_tests.sh $(BUILD) $(TESTS)
	@sh tests/cli/memory_city.sh $(BUILD)/polarlux
	@$(MAKE) --no-print-directory check-examples check-python check-install

check-build:
	@$(MAKE) --no-print-directory deps
	@$(MAKE) --no-print-directory -j$(JOBS) all $(TESTS) $(EXAMPLES) check-core-headers check-lib-split check-man \
	  check-no-install check-layers $(BUILD)/tests/failwrite.so

# The include rule (tests/check_layers.sh): stages in data-flow order base <
# scene < polar < light < photon < render < api, base/engine.h only in
# src/api and src/base, no circles between files.
check-layers:
	@sh tests/check_layers.sh

# examples/: programs that embed the engine as an application would. Each
# links the core library alone (no port, no libpng, no pthreads, no cJSON)
# and checks its own results: make check runs them.
EXAMPLES = $(patsubst examples/%.c,$(BUILD)/examples/%,$(wildcard examples/*.c))
$(BUILD)/examples/%: examples/%.c $(LIB_A)
	@mkdir -p $(@D)
	$(CC) -Iinclude $(CFLAGS_ALL) -o $@ $< $(LIB_A) $(CORE_LIBS)

# man/polarlux.1 is generated from the command's --help texts (man/mkman.sh)
# and kept in the repository; check-man fails when it is not current. The
# page describes the command with OSMesa: a build without it (OSMESA=0, or
# no libosmesa6-dev) is compared with its one line on OSMesa read as such.
man: $(BIN)
	sh man/mkman.sh $(BIN) > man/polarlux.1

check-man: $(BIN)
	@sh man/mkman.sh $(BIN) | sed 's/not built into this polarlux/built in/' > $(BUILD)/polarlux.1
	@cmp -s $(BUILD)/polarlux.1 man/polarlux.1 || { diff man/polarlux.1 $(BUILD)/polarlux.1 | head -20; \
	  echo "check-man: man/polarlux.1 is not the current --help text: run 'make man' and commit it"; exit 1; }

# python/: the ctypes package over $(LIB_SO), tested with Debian's pytest and
# numpy (/usr/bin/python3: a python3 earlier on PATH may not see them). A
# run that collects no tests (pytest's exit 5) fails. Sanitizer builds skip
# it, saying so: the interpreter cannot load an instrumented library.
PYTHON ?= /usr/bin/python3
# tests/abi_sizes.c prints the C layout of the structures the package mirrors
# with ctypes; python/tests/test_abi.py compares it (and runs first).
ABI_SIZES = $(BUILD)/tests/abi_sizes
$(ABI_SIZES): tests/abi_sizes.c include/polarlux.h include/polarlux_port.h
	@mkdir -p $(@D)
	$(CC) -Iinclude $(CFLAGS_ALL) -o $@ $<
check-python: $(LIB_SO) $(BIN) $(ABI_SIZES)
	@case "$(EXTRA_CFLAGS)" in *sanitize*) \
	  echo "python: skipped in this sanitizer build (make check runs it)"; exit 0;; esac; \
	log=$(CURDIR)/$(BUILD)/python-tests.log; \
	(cd python && PYTHONDONTWRITEBYTECODE=1 POLARLUX_LIB=$(CURDIR)/$(LIB_SO) POLARLUX_BIN=$(CURDIR)/$(BIN) \
	  POLARLUX_ABI_SIZES=$(CURDIR)/$(ABI_SIZES) \
	  $(PYTHON) -m pytest -q -rs -p no:cacheprovider tests) >$$log 2>&1; rc=$$?; \
	if [ $$rc -eq 5 ]; then echo "python: pytest collected no tests (exit 5)"; exit 1; fi; \
	if [ $$rc -ne 0 ]; then cat $$log; echo "python: FAILED (pytest exit $$rc)"; exit 1; fi; \
	echo "ok   python: $$(tail -1 $$log)"

check-examples: $(EXAMPLES)
	@for x in $(EXAMPLES); do \
	  $$x >$$x.log 2>&1 || { cat $$x.log; echo "example $$x: FAILED"; exit 1; }; \
	  echo "ok   example $$(basename $$x): $$(grep -c '^ok ' $$x.log) checks"; \
	done

# The failing-disk stand-in of tests/cli/hostile.sh (an LD_PRELOAD shim).
$(BUILD)/tests/failwrite.so: tests/cli/failwrite.c
	@mkdir -p $(@D)
	$(CC) -O1 -g -fPIC -shared -Wall -Wextra -Werror -o $@ $< -ldl

# The hostile corpus (tests/cli/hostile.sh) under valgrind memcheck, for CI
# (.ci/run). Since OSMesa is opened on first use, a case starts in about
# 1.2 s of CPU under valgrind (it was 13 s with libLLVM mapped at start).
check-hostile-valgrind: all $(BUILD)/tests/failwrite.so
	@PLX_HOSTILE_TIMEOUT=900 PLX_HOSTILE_WRAP="valgrind -q --error-exitcode=9 --leak-check=full --errors-for-leak-kinds=definite --suppressions=$(CURDIR)/tests/valgrind.supp" \
	  sh tests/cli/hostile.sh $(BUILD)/polarlux

unit: $(TESTS)
	@for t in $(TESTS); do $$t || exit 1; done

# The core library stands alone: libpolarlux.a asks only for libm and the C
# functions a bare-metal libc has (the list of check-freestanding) and never
# for cJSON, libpng, pthreads or stdio; libpolarlux.so needs only libm and
# libc, and carries its SONAME.
LIB_ALLOWED_RE = ^(sincos|_GLOBAL_OFFSET_TABLE_|__stack_chk_fail|__[a-z_]+_chk|__(asan|ubsan|sanitizer|sancov|lsan)_[A-Za-z0-9_]+|__sanitizer_cov_.*)$$
check-lib-split: $(LIB_A) $(LIB_SO) $(PORT_A)
	@for l in $(LIB_A) $(PORT_A); do \
	  bad=$$(nm -g --defined-only $$l | awk 'NF==3{print $$3}' | grep -v '^plx_' | head -5); \
	  [ -z "$$bad" ] || { echo "check-lib-split: $$l exports names that are not plx_*:" $$bad; exit 1; }; done; \
	bad=$$(nm -D --defined-only $(LIB_SO_REAL) | awk 'NF==3 && $$2 != "A"{print $$3}' | grep -v '^plx_' | head -5); \
	[ -z "$$bad" ] || { echo "check-lib-split: libpolarlux.so exports names that are not plx_*:" $$bad; exit 1; }; \
	mkdir -p $(BUILD)/tests && \
	$(CC) -std=c99 -Wall -Wextra -Werror $(EXTRA_CFLAGS) -Iinclude -o $(BUILD)/tests/own_names tests/embed/own_names.c $(PORT_A) $(LIB_A) \
	  -lpng -lz -lpthread -lm && $(BUILD)/tests/own_names >/dev/null && \
	$(CC) -std=c99 $(EXTRA_CFLAGS) -Iinclude -o $(BUILD)/tests/own_names_so tests/embed/own_names.c $(PORT_A) -L$(BUILD) -lpolarlux \
	  -lpng -lz -lpthread -lm && LD_LIBRARY_PATH=$(BUILD) $(BUILD)/tests/own_names_so >/dev/null || \
	  { echo "check-lib-split: an application's own arena_alloc, camera_setup, port_now_ns clash with the library"; exit 1; }
	@t=$$(mktemp -d); \
	nm -u $(LIB_A) | awk 'NF==2{print $$2}' | sort -u >$$t/u; \
	nm --defined-only $(LIB_A) | awk 'NF==3{print $$3}' | sort -u >$$t/d; \
	bad=$$(comm -23 $$t/u $$t/d | grep -vE '$(LIB_ALLOWED_RE)' | grep -vxF "$$(printf '%s\n' $(FS_ALLOWED))"); \
	rm -rf $$t; \
	if [ -n "$$bad" ]; then echo "check-lib-split: libpolarlux.a needs symbols outside the core's allowance:" $$bad; exit 1; fi; \
	needed=$$(readelf -d $(LIB_SO_REAL) | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p' | tr '\n' ' '); \
	for n in $$needed; do case $$n in libm.so.*|libc.so.*) ;; \
	  *) echo "check-lib-split: libpolarlux.so needs $$n"; exit 1;; esac; done; \
	soname=$$(readelf -d $(LIB_SO_REAL) | sed -n 's/.*(SONAME).*\[\(.*\)\]/\1/p'); \
	[ "$$soname" = "$(SONAME)" ] || { echo "check-lib-split: SONAME '$$soname', want $(SONAME)"; exit 1; }; \
	[ "$$(readlink $(LIB_SO))" = "$(SONAME)" ] && [ "$$(readlink $(BUILD)/$(SONAME))" = "$(notdir $(LIB_SO_REAL))" ] || \
	  { echo "check-lib-split: $(LIB_SO) -> $(SONAME) -> $(notdir $(LIB_SO_REAL)) links are wrong"; exit 1; }

# The core may include only these C headers: no I/O, no OS.
check-core-headers:
	@bad=$$(grep -nE '^[[:space:]]*#[[:space:]]*include[[:space:]]*<' $(CORE_SRC) $(foreach d,$(CORE_DIRS),$(wildcard src/$(d)/*.h)) | \
	  grep -vE '<(stddef|stdint|string|math|float|limits|stdarg|stdlib)\.h>' || true); \
	if [ -n "$$bad" ]; then echo "core includes a platform header:"; echo "$$bad"; exit 1; fi; \
	if grep -nE '\b(malloc|calloc|realloc|free)[[:space:]]*\(' $(CORE_SRC) | grep -v '^src/scene/geojson.c:.*json_' ; then \
	  echo "core calls the C heap (see above)"; exit 1; fi

asan:
	$(MAKE) BUILD=build/asan OPT="-O1 -g -fno-omit-frame-pointer" SKIP_SLOW= \
	  EXTRA_CFLAGS="-fsanitize=address,undefined -fno-sanitize-recover=all -DPLX_DEBUG" check

valgrind: all $(TESTS)
	@for t in $(TESTS); do \
	  echo "valgrind $$t"; \
	  PLX_TEST_QUICK=1 PLX_TEST_SKIP_SLOW= valgrind -q --error-exitcode=9 --leak-check=full --errors-for-leak-kinds=definite --suppressions=tests/valgrind.supp $$t >/dev/null || exit 1; \
	done; echo "valgrind: clean"

# The refactor check (not part of make check: it builds another revision):
# every command on every fixture and two generated cities, byte for byte
# against revision BASE (tests/check_identical.sh).
BASE ?= 73d3a0e
check-identical:
	@sh tests/check_identical.sh $(BASE)

bench: all $(BENCHES)
	@for b in $(BENCHES); do echo "== $$b"; $$b || exit 1; done

# ---- install ------------------------------------------------------------------
# Two pkg-config files: polarlux (the core: libm) and
# polarlux-port (the POSIX port and PNG files, which add libpng and pthreads).
install: all
	install -d $(DESTDIR)$(PREFIX)/lib $(DESTDIR)$(PREFIX)/include $(DESTDIR)$(PREFIX)/bin \
	  $(DESTDIR)$(PREFIX)/lib/pkgconfig
	install -m 644 $(LIB_A) $(PORT_A) $(DESTDIR)$(PREFIX)/lib/
	install -m 755 $(LIB_SO_REAL) $(DESTDIR)$(PREFIX)/lib/
	ln -sf $(notdir $(LIB_SO_REAL)) $(DESTDIR)$(PREFIX)/lib/$(SONAME)
	ln -sf $(SONAME) $(DESTDIR)$(PREFIX)/lib/libpolarlux.so
	install -m 644 include/polarlux.h include/polarlux_port.h $(DESTDIR)$(PREFIX)/include/
	install -m 755 $(BIN) $(DESTDIR)$(PREFIX)/bin/
	install -d $(DESTDIR)$(PREFIX)/share/man/man1
	install -m 644 man/polarlux.1 $(DESTDIR)$(PREFIX)/share/man/man1/
	printf '%s\n' 'prefix=$(PREFIX)' 'libdir=$${prefix}/lib' 'includedir=$${prefix}/include' '' \
	  'Name: polarlux' 'Description: exact night lighting of 2.5D cities (portable core)' \
	  'Version: $(VERSION)' 'Libs: -L$${libdir} -lpolarlux' 'Libs.private: $(CORE_LIBS)' \
	  'Cflags: -I$${includedir}' \
	  > $(DESTDIR)$(PREFIX)/lib/pkgconfig/polarlux.pc
	printf '%s\n' 'prefix=$(PREFIX)' 'libdir=$${prefix}/lib' 'includedir=$${prefix}/include' '' \
	  'Name: polarlux-port' 'Description: polarlux POSIX port and PNG/PFM files' \
	  'Version: $(VERSION)' 'Requires: polarlux' 'Libs: -L$${libdir} -lpolarlux-port $(PORT_LIBS)' \
	  'Cflags: -I$${includedir}' \
	  > $(DESTDIR)$(PREFIX)/lib/pkgconfig/polarlux-port.pc

# The installed tree as an embedder uses it: pkg-config's flags build and
# run tests/embed/own_names.c against the installed port (static: its
# libraries are in Libs, not Libs.private, which only --static prints) and
# core (the .so).
check-install: all
	@t=$$(mktemp -d); \
	$(MAKE) --no-print-directory install PREFIX=$$t >/dev/null && \
	$(CC) -std=c99 $(EXTRA_CFLAGS) -o $$t/own tests/embed/own_names.c \
	  $$(PKG_CONFIG_PATH=$$t/lib/pkgconfig pkg-config --cflags --libs polarlux-port) && \
	LD_LIBRARY_PATH=$$t/lib $$t/own >/dev/null && { echo "ok   install: pkg-config polarlux-port builds and runs an embedder"; rm -rf $$t; } || \
	{ echo "check-install: make install, building tests/embed/own_names.c with pkg-config --cflags --libs polarlux-port, or running it failed"; rm -rf $$t; exit 1; }

clean:
	rm -rf build

include tests/hardening.mk

# ---- web map demo (Leaflet from the npm registry, served on 127.0.0.1) ---------
# make web-deps   npm ci in web/ (Leaflet into web/node_modules; needs npm)
# make web-data   tiles, the best-lit route and the scene for the page, in web/data
# make web-demo   both, then serves web/ on http://127.0.0.1:$(WEB_PORT)/
# make check-web  headless Chromium screenshot of the page, checked by its pixels
WEB_PORT  ?= 8765
WEB_SCENE ?= fixtures/helsinki-centre.geojson
WEB_NET   ?= fixtures/helsinki-streets.geojson
WEB_FROM  ?= 24.9400,60.1660
WEB_TO    ?= 24.9480,60.1770
.PHONY: web-deps web-data web-demo check-web

web-deps: web/node_modules/leaflet/dist/leaflet.js

web/node_modules/leaflet/dist/leaflet.js: web/package.json web/package-lock.json
	cd web && npm ci --no-audit --no-fund
	@touch $@

web-data: $(BIN)
	@mkdir -p web/data
	$(BIN) tiles $(WEB_SCENE) --quiet --zoom 14-17 -o web/data/tiles
	$(BIN) tiles $(WEB_SCENE) --quiet --zoom 14-17 --quantity sc -o web/data/tiles-sc
	$(BIN) route $(WEB_SCENE) --quiet --network $(WEB_NET) --from $(WEB_FROM) --to $(WEB_TO) \
	  --geojson web/data/route.geojson
	cp $(WEB_SCENE) web/data/scene.geojson

web-demo: web-deps web-data
	@echo "serving web/ on http://127.0.0.1:$(WEB_PORT)/ (Ctrl-C stops)"
	cd web && python3 -m http.server $(WEB_PORT) --bind 127.0.0.1

check-web: web-deps web-data
	@sh tests/web/check_web.sh web build/web
