# The OSMesa port of the renderer's raster pass (port/osmesa/plx_osmesa.h),
# included by the Makefile. Built only when pkg-config knows osmesa AND the
# compiler in use can link it (so cross builds and builds without
# libosmesa6-dev go on without it); `make OSMESA=0` leaves it out by hand.
# When built:
#  - build/libpolarlux_osmesa.a holds glraster.o (GL calls, no context) and
#    plx_osmesa.o (the OSMesa context); libpolarlux itself never needs GL;
#  - the CLI's render command and the render test and bench are compiled with
#    -DPLX_HAVE_OSMESA and linked with that archive and -ldl: libOSMesa
#    itself is opened with dlopen on the first `--backend osmesa` frame
#    (port/osmesa/gl_api.h says why), so other commands never load it.
OSMESA ?= auto
ifeq ($(OSMESA),auto)
OSMESA := $(shell pkg-config --exists osmesa 2>/dev/null && \
  printf 'int main(void){return 0;}\n' | $(CC) -x c - -o /dev/null $$(pkg-config --libs osmesa) \
  >/dev/null 2>&1 && echo 1 || echo 0)
endif

# Objects that change with the setting are rebuilt when it changes.
OSMESA_CLIENTS = $(BUILD)/src/cli/cmd_render.o $(BUILD)/tests/unit/test_render.o \
                 $(BUILD)/tests/bench/bench_render.o
# The stamp holds the setting and is rewritten (its time moved) only when
# the setting changes; it always exists, so the Makefile's .SECONDARY does
# not let a missing stamp pass for an up-to-date one.
OSMESA_STAMP   = $(BUILD)/.osmesa
$(shell mkdir -p $(BUILD) && [ "$$(cat $(OSMESA_STAMP) 2>/dev/null)" = "$(OSMESA)" ] || \
  echo "$(OSMESA)" > $(OSMESA_STAMP))
$(OSMESA_CLIENTS): $(OSMESA_STAMP)
$(OSMESA_STAMP): ;

ifeq ($(OSMESA),1)
OSMESA_CFLAGS := $(shell pkg-config --cflags osmesa)
OSMESA_LIBS   := -ldl
OSMESA_SRC     = $(wildcard port/osmesa/*.c)
OSMESA_OBJ     = $(OSMESA_SRC:%.c=$(BUILD)/%.o)
OSMESA_A       = $(BUILD)/libpolarlux_osmesa.a
# the programs that may use it
OSMESA_USERS   = $(BIN) $(BUILD)/tests/test_render $(BUILD)/bench/bench_render

$(OSMESA_OBJ): CPPFLAGS += -Iport/osmesa $(OSMESA_CFLAGS)
$(OSMESA_CLIENTS): CPPFLAGS += -DPLX_HAVE_OSMESA -Iport/osmesa

$(OSMESA_A): $(OSMESA_OBJ)
	@rm -f $@
	ar rcs $@ $^

# Mesa keeps a few blocks for the process's life: not ours to report
# (LeakSanitizer is told in plx_osmesa.c, valgrind here).
export VALGRIND_OPTS := $(VALGRIND_OPTS) --suppressions=$(CURDIR)/port/osmesa/valgrind.supp

$(OSMESA_USERS): $(OSMESA_A)
$(OSMESA_USERS): LIBS := $(OSMESA_A) $(OSMESA_LIBS) $(LIBS)
endif
