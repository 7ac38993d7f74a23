# polarlux — build, test and install. See README.md.
#
#   make            libraries (build/libpolarlux.a, .so) and build/polarlux
#   make demo       build and run the main job on the bundled fixtures
#   make check      unit + command-line tests, quick (long loops shortened)
#   make check-full the same with the full loops and bounds (a few minutes)
#   make asan       the same tests under AddressSanitizer + UBSan
#   make valgrind   the unit tests under valgrind memcheck
#   make bench      benchmarks (tests/bench)
#   make deps       install missing Debian packages (apt-get when root)
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
LIBS     = -lcjson -lpng -lm -lpthread

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

LIB_A  = $(BUILD)/libpolarlux.a
LIB_SO = $(BUILD)/libpolarlux.so
BIN    = $(BUILD)/polarlux

VERSION = $(shell sed -n 's/^\#define PLX_VERSION_STRING "\(.*\)"/\1/p' include/polarlux.h)
DEB_PACKAGES = libcjson-dev libcmocka-dev libpng-dev pkg-config

.SECONDARY:
.PHONY: all deps demo check check-full check-build check-hostile-valgrind unit cli-test asan valgrind bench install clean \
        check-core-headers

all: $(LIB_A) $(LIB_SO) $(BIN)

# ---- dependencies ------------------------------------------------------------
deps:
	@missing=""; for p in $(DEB_PACKAGES); do \
	  dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q "ok installed" || missing="$$missing $$p"; \
	done; \
	if [ -z "$$missing" ]; then exit 0; fi; \
	if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null; then \
	  echo "make deps: installing$$missing"; \
	  (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq$$missing) >/dev/null || \
	  { echo "make deps: apt-get failed; run: apt-get install$$missing" >&2; exit 1; }; \
	else \
	  echo "make deps: missing packages; run as root: apt-get install$$missing" >&2; exit 1; \
	fi

# ---- objects -----------------------------------------------------------------
$(BUILD)/src/%.o: src/%.c | deps
	@mkdir -p $(@D)
	$(CC) $(CPPFLAGS) $(CFLAGS_ALL) -c $< -o $@

$(BUILD)/src/cli/%.o: src/cli/%.c | deps
	@mkdir -p $(@D)
	$(CC) $(CPPFLAGS) $(POSIX) $(CFLAGS_ALL) -c $< -o $@

$(BUILD)/port/%.o: port/%.c | deps
	@mkdir -p $(@D)
	$(CC) $(CPPFLAGS) $(POSIX) $(CFLAGS_ALL) -c $< -o $@

$(BUILD)/tests/%.o: tests/%.c | deps
	@mkdir -p $(@D)
	$(CC) $(CPPFLAGS) -Itests/ref $(POSIX) $(CFLAGS_ALL) -c $< -o $@

$(LIB_A): $(CORE_OBJ) $(PORT_OBJ)
	@rm -f $@
	ar rcs $@ $^

$(LIB_SO): $(CORE_OBJ) $(PORT_OBJ)
	$(CC) -shared \
	  -o $@ $^ $(LIBS)

$(BIN): $(CLI_OBJ) $(LIB_A)
	$(CC) $(CFLAGS_ALL) -o $@ $(CLI_OBJ) $(LIB_A) $(LIBS)

$(BUILD)/tests/test_%: $(BUILD)/tests/unit/test_%.o $(REF_OBJ) $(LIB_A)
	$(CC) $(CFLAGS_ALL) -o $@ $< $(REF_OBJ) $(LIB_A) -lcmocka $(LIBS)

$(BUILD)/bench/bench_%: $(BUILD)/tests/bench/bench_%.o $(REF_OBJ) $(LIB_A)
	@mkdir -p $(@D)
	$(CC) $(CFLAGS_ALL) -o $@ $< $(REF_OBJ) $(LIB_A) $(LIBS)

-include port/osmesa/osmesa.mk
-include $(shell find $(BUILD) -name '*.d' 2>/dev/null)

# ---- the main job -------------------------------------------------------------
demo: all
	@sh tests/demo.sh $(BIN)

# ---- tests --------------------------------------------------------------------
# make check: the quick suite (long random loops shortened by
# PLX_TEST_QUICK; well under a minute), built and run in parallel.
# make check-full: the full loops and bounds the issues ask for (12,000
# visibility points against the brute force, photon accuracy at the default
# photon count, ...); a few minutes. CI runs both.
check: check-build
	@PLX_TEST_QUICK=1 sh tests/run_tests.sh $(BUILD) $(TESTS)

check-full: check-build
	@sh tests/run_tests.sh $(BUILD) $(TESTS)

check-build:
	@$(MAKE) --no-print-directory -j$(JOBS) all $(TESTS) check-core-headers $(BUILD)/tests/failwrite.so

# The failing-disk stand-in of tests/cli/hostile.sh (an LD_PRELOAD shim).
$(BUILD)/tests/failwrite.so: tests/cli/failwrite.c
	@mkdir -p $(@D)
	$(CC) -O1 -g -fPIC -shared -Wall -Wextra -Werror -o $@ $< -ldl

# The hostile corpus (tests/cli/hostile.sh) under valgrind memcheck, for CI.
check-hostile-valgrind: check-build
	@PLX_HOSTILE_WRAP="valgrind -q --error-exitcode=9 --leak-check=full --errors-for-leak-kinds=definite" \
	  sh tests/cli/hostile.sh $(BUILD)/polarlux

unit: $(TESTS)
	@for t in $(TESTS); do $$t || exit 1; done

# The core may include only these C headers: no I/O, no OS.
check-core-headers:
	@bad=$$(grep -nE '^[[:space:]]*#[[:space:]]*include[[:space:]]*<' $(CORE_SRC) $(foreach d,$(CORE_DIRS),$(wildcard src/$(d)/*.h)) | \
	  grep -vE '<(stddef|stdint|string|math|float|limits|stdarg|stdlib|cjson/cJSON)\.h>' || true); \
	if [ -n "$$bad" ]; then echo "core includes a platform header:"; echo "$$bad"; exit 1; fi; \
	if grep -nE '\b(malloc|calloc|realloc|free)[[:space:]]*\(' $(CORE_SRC) | grep -v '^src/scene/geojson.c:.*json_' ; then \
	  echo "core calls the C heap (see above)"; exit 1; fi

asan:
	$(MAKE) BUILD=build/asan OPT="-O1 -g -fno-omit-frame-pointer" \
	  EXTRA_CFLAGS="-fsanitize=address,undefined -fno-sanitize-recover=all" check

valgrind: all $(TESTS)
	@for t in $(TESTS); do \
	  echo "valgrind $$t"; \
	  PLX_TEST_QUICK=1 valgrind -q --error-exitcode=9 --leak-check=full --errors-for-leak-kinds=definite $$t >/dev/null || exit 1; \
	done; echo "valgrind: clean"

bench: all $(BENCHES)
	@for b in $(BENCHES); do echo "== $$b"; $$b || exit 1; done

# ---- install ------------------------------------------------------------------
install: all
	install -d $(DESTDIR)$(PREFIX)/lib $(DESTDIR)$(PREFIX)/include $(DESTDIR)$(PREFIX)/bin \
	  $(DESTDIR)$(PREFIX)/lib/pkgconfig
	install -m 644 $(LIB_A) $(DESTDIR)$(PREFIX)/lib/
	install -m 755 $(LIB_SO) $(DESTDIR)$(PREFIX)/lib/
	install -m 644 include/polarlux.h $(DESTDIR)$(PREFIX)/include/
	install -m 755 $(BIN) $(DESTDIR)$(PREFIX)/bin/
	printf '%s\n' 'prefix=$(PREFIX)' 'libdir=$${prefix}/lib' 'includedir=$${prefix}/include' '' \
	  'Name: polarlux' 'Description: exact night lighting of 2.5D cities' \
	  'Version: $(VERSION)' 'Libs: -L$${libdir} -lpolarlux' 'Libs.private: $(LIBS)' \
	  'Requires.private: libcjson libpng' 'Cflags: -I$${includedir}' \
	  > $(DESTDIR)$(PREFIX)/lib/pkgconfig/polarlux.pc

clean:
	rm -rf build

include tests/hardening.mk
