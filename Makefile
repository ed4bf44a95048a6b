# Minko: portable C99 collision detection. Hand-written Makefile.
#
#   make lib        build/libminko.a + build/libminko.so.MAJOR (C99 compiler + libm only)
#   make check      every test, in double, single and ASan+UBSan builds
#   make demo       headless side-by-side demo against Bullet, ODE, libccd
#   make bench      all benchmarks, JSON Lines into build/bench/
#   make install    PREFIX=/usr/local DESTDIR= (headers, libs, minko.pc)
#
# Options: PRECISION=double|single, SAN=1 (ASan+UBSan), MK_WITHOUT="module ..."
# (leave whole modules out of the library, e.g. MK_WITHOUT="toi hgrid").
# CFLAGS/LDFLAGS from the environment are appended to, never replaced.

.DEFAULT_GOAL := lib
.SUFFIXES:
.DELETE_ON_ERROR:

VERSION_MAJOR := $(shell sed -n 's/^\#define MK_VERSION_MAJOR *\([0-9]*\).*/\1/p' include/minko/base.h)
VERSION_MINOR := $(shell sed -n 's/^\#define MK_VERSION_MINOR *\([0-9]*\).*/\1/p' include/minko/base.h)
VERSION_PATCH := $(shell sed -n 's/^\#define MK_VERSION_PATCH *\([0-9]*\).*/\1/p' include/minko/base.h)
VERSION := $(VERSION_MAJOR).$(VERSION_MINOR).$(VERSION_PATCH)

PRECISION ?= double
SAN ?= 0
ifeq ($(PRECISION),double)
  B := build
else ifeq ($(PRECISION),single)
  B := build/single
else
  $(error PRECISION must be double or single, not '$(PRECISION)')
endif
ifeq ($(SAN),1)
  B := $(B)-san
  ifeq ($(B),build-san)
    B := build/san
  endif
endif
# A build that leaves modules out has different objects: its own directory.
ifneq ($(strip $(MK_WITHOUT)),)
  B := $(B)/without-$(shell echo $(MK_WITHOUT) | tr ' ' '-')
endif

JOBS ?= $(shell nproc 2>/dev/null || echo 2)
# V=1 shows full command lines.
V ?= 0
ifeq ($(V),1)
  Q :=
  say = @true
else
  Q := @
  say = @printf '  %-6s %s\n'
endif
CC ?= cc
CXX ?= c++
CFLAGS ?= -O2 -g
CXXFLAGS ?= -O2 -g
PKG_CONFIG ?= pkg-config

WARN := -Wall -Wextra -Werror -Wshadow -Wstrict-prototypes -Wmissing-prototypes -Wpointer-arith -Wundef
# -ffp-contract=off: no fused multiply-adds behind our back, so results do not
# change with the compiler's mood and tests stay bit-reproducible.
FP := -ffp-contract=off -fno-math-errno
SAN_FLAGS := -fsanitize=address,undefined,float-divide-by-zero,float-cast-overflow -fno-sanitize-recover=all -fno-omit-frame-pointer
ifeq ($(SAN),1)
  FP += $(SAN_FLAGS)
  LDSAN := $(SAN_FLAGS)
endif
INC := -I$(B)/include -Iinclude
LIB_CFLAGS := -std=c99 -pedantic $(WARN) $(FP) -fvisibility=hidden -fPIC -DMK_BUILDING $(INC) $(CFLAGS)
# Tests and demos: C99 without -pedantic (Check's macros use empty variadic arguments).
APP_CFLAGS := -std=c99 $(WARN) -Wno-missing-prototypes $(FP) $(INC) -Isrc $(CFLAGS)
APP_CXXFLAGS := -std=c++11 -Wall -Wextra -Werror $(FP) $(INC) -Isrc $(CXXFLAGS)

# ---- the library -------------------------------------------------------------
MK_WITHOUT ?=
LIB_SRCS := $(filter-out $(patsubst %,src/%.c,$(MK_WITHOUT)),$(wildcard src/*.c))
LIB_OBJS := $(LIB_SRCS:src/%.c=$(B)/obj/%.o)
WITHOUT_DEFS := $(foreach m,$(MK_WITHOUT),-DMK_WITHOUT_$(shell echo $(m) | tr a-z A-Z))
LIB_CFLAGS += $(WITHOUT_DEFS)
CONFIG_H := $(B)/include/minko/config.h
STATIC_LIB := $(B)/libminko.a
SHARED_LIB := $(B)/libminko.so.$(VERSION)
SONAME := libminko.so.$(VERSION_MAJOR)

$(CONFIG_H): include/minko/config.h.in Makefile
	@mkdir -p $(@D)
	$(Q)sed 's/@PRECISION@/$(PRECISION)/' $< > $@

$(B)/obj/%.o: src/%.c $(CONFIG_H)
	@mkdir -p $(@D)
	$(say) CC $@
	$(Q)$(CC) $(LIB_CFLAGS) -MMD -MP -c $< -o $@

$(STATIC_LIB): $(LIB_OBJS)
	$(say) AR $@
	$(Q)rm -f $@
	$(Q)$(AR) rcs $@ $^

$(SHARED_LIB): $(LIB_OBJS)
	$(say) LD $@
	$(Q)$(CC) -shared -Wl,-soname,$(SONAME) $(LDSAN) $(LDFLAGS) -o $@ $^ -lm
	$(Q)ln -sf libminko.so.$(VERSION) $(B)/$(SONAME)
	$(Q)ln -sf $(SONAME) $(B)/libminko.so

$(B)/.exports-ok: $(SHARED_LIB) scripts/check-exports.sh $(wildcard include/minko/*.h)
	$(Q)scripts/check-exports.sh $(SHARED_LIB)
	@touch $@

.PHONY: lib
lib: $(STATIC_LIB) $(SHARED_LIB) $(B)/.exports-ok

-include $(LIB_OBJS:.o=.d)

# ---- external dependencies (only for check, demo, bench) -------------------
.PHONY: deps
deps:
	@scripts/install-deps.sh --check || scripts/install-deps.sh

# Evaluated lazily, after `deps` has run.
CHECK_LIBS = $(shell $(PKG_CONFIG) --libs check)
CHECK_CFLAGS = $(shell $(PKG_CONFIG) --cflags check)

# ---- tests -------------------------------------------------------------------
# Every tests/test_*.c is one Check program; tests/support/*.c is linked into all.
TEST_SRCS := $(wildcard tests/test_*.c)
TEST_BINS := $(TEST_SRCS:tests/%.c=$(B)/tests/%)
TSUP_SRCS := $(wildcard tests/support/*.c)
TSUP_OBJS := $(TSUP_SRCS:tests/support/%.c=$(B)/tests/support/%.o)

$(B)/tests/support/%.o: tests/support/%.c $(CONFIG_H)
	@mkdir -p $(@D)
	$(say) CC $@
	$(Q)$(CC) $(APP_CFLAGS) -Itests $(CHECK_CFLAGS) -MMD -MP -c $< -o $@

$(B)/tests/%: tests/%.c $(TSUP_OBJS) $(STATIC_LIB)
	@mkdir -p $(@D)
	$(say) CCLD $@
	$(Q)$(CC) $(APP_CFLAGS) -Itests $(CHECK_CFLAGS) -MMD -MP $< $(TSUP_OBJS) $(STATIC_LIB) $(LDSAN) $(LDFLAGS) $(CHECK_LIBS) -lm -o $@

-include $(TEST_BINS:%=%.d) $(TSUP_OBJS:.o=.d)

# The C example in README.md must compile (strict C99) and run.
$(B)/readme/example: README.md $(STATIC_LIB)
	@mkdir -p $(@D)
	$(say) CCLD $@
	$(Q)awk '/^```c/{f=1;next} /^```/{if(f)exit} f' README.md > $(B)/readme/example.c
	$(Q)$(CC) -std=c99 -pedantic $(WARN) $(FP) $(INC) $(CFLAGS) $(B)/readme/example.c $(STATIC_LIB) $(LDSAN) -lm -o $@

# Every public header compiles alone as C99 and as C++11.
$(B)/.headers-ok: $(wildcard include/minko/*.h) $(CONFIG_H)
	@mkdir -p $(B)/hdr
	@for h in include/minko/*.h; do n=$$(basename $$h .h); \
	  printf '#include "minko/%s.h"\nint mk_hdr_%s_dummy(void);\nint mk_hdr_%s_dummy(void) { return 0; }\n' $$n $$n $$n > $(B)/hdr/$$n.c; \
	  cp $(B)/hdr/$$n.c $(B)/hdr/$$n.cc; \
	  $(CC) -std=c99 -pedantic $(WARN) $(INC) -c $(B)/hdr/$$n.c -o $(B)/hdr/$$n.o || exit 1; \
	  $(CXX) -std=c++11 -pedantic -Wall -Wextra -Werror $(INC) -c $(B)/hdr/$$n.cc -o $(B)/hdr/$$n.oo || exit 1; \
	done
	@echo "headers: each public header compiles alone as C99 and C++11"
	@touch $@

.PHONY: tests test-run
tests: lib $(TEST_BINS) $(B)/readme/example $(B)/.headers-ok $(CHECK_BINS)
test-run: tests
	@fail=0; for t in $(TEST_BINS) $(CHECK_BINS); do \
	  echo "== $$t"; \
	  CK_FORK=no $$t || fail=1; \
	done; \
	echo "== $(B)/readme/example"; $(B)/readme/example || fail=1; \
	if [ $$fail -ne 0 ]; then echo "FAILED: $(B)"; exit 1; fi; \
	echo "all tests passed: $(B)"

.PHONY: check
check: deps
	$(MAKE) -j$(JOBS) PRECISION=double SAN=0 test-run
	$(MAKE) -j$(JOBS) PRECISION=single SAN=0 test-run
	$(MAKE) -j$(JOBS) PRECISION=double SAN=1 test-run
	$(MAKE) -j$(JOBS) PRECISION=single SAN=1 test-run
	$(MAKE) -j$(JOBS) PRECISION=double SAN=0 MK_WITHOUT="gjk epa sat" without-run
	scripts/check-abi.sh "$(CC)"
	@echo "make check: all passed"

# The library without the iterative narrowphase must link, and the closed
# forms must still answer (run by make check with MK_WITHOUT="gjk epa sat").
.PHONY: without-run
without-run: lib $(B)/tests/closed_forms_only
	$(B)/tests/closed_forms_only
$(B)/tests/closed_forms_only: tests/without/closed_forms_only.c $(STATIC_LIB)
	@mkdir -p $(@D)
	$(say) CCLD $@
	$(Q)$(CC) -std=c99 -pedantic $(WARN) $(FP) $(INC) $(WITHOUT_DEFS) $(CFLAGS) $< $(STATIC_LIB) -lm -o $@

# ---- demos, benchmarks, adapters: each area brings its own fragment ----------
# A fragment registers itself by appending, e.g.
#   DEMO_BINS  += $(B)/demos/bench_broadphase
#   BENCH_RUNS += $(call mk_run,$(B)/demos/bench_broadphase --json $(BENCH_DIR)/broad.jsonl)
#   DEMO_RUNS  += $(call mk_run,$(B)/demos/bench_broadphase --quick)
#   CHECK_BINS += $(B)/tests/adapter_runner      (extra test programs, run by test-run)
# mk_run turns one command line into an echoed, ';'-terminated shell step, so
# commands with arguments survive being collected in one variable. The steps
# run one after another: benchmarks never share the CPU with each other.
mk_run = $(eval MK_RUN_TALLY += x x $(foreach w,$(1) $(1),x))echo '>> $(strip $(1))'; $(strip $(1));
BENCH_DIR := $(B)/bench
DEMO_BINS :=
BENCH_RUNS :=
DEMO_RUNS :=
CHECK_BINS :=
-include $(sort $(wildcard demos/*.mk adapters/*/*.mk))
# A fragment that appends a bare command instead of $(call mk_run,...) glues
# it onto its neighbour's arguments and breaks `make demo` / `make bench`.
# mk_run keeps a tally with as many words as each step it writes, so any
# word that did not come through mk_run is caught when the Makefile is read
# (make check reads it too).
ifneq ($(words $(DEMO_RUNS) $(BENCH_RUNS)),$(words $(MK_RUN_TALLY)))
$(error DEMO_RUNS or BENCH_RUNS has a command not wrapped in $$(call mk_run,...): check demos/*.mk and adapters/*/*.mk)
endif
# The `tests` rule above was read before the fragments filled CHECK_BINS.
tests: $(CHECK_BINS)

.PHONY: demo-build bench demo
demo-build: lib $(DEMO_BINS)
bench: deps
	$(MAKE) -j$(JOBS) demo-build
	@mkdir -p $(BENCH_DIR)
	@set -e; $(BENCH_RUNS) echo "bench: JSON Lines in $(BENCH_DIR)/"
	@demos/report.sh $(BENCH_DIR)
demo: deps
	$(MAKE) -j$(JOBS) demo-build
	@mkdir -p $(BENCH_DIR)
	@set -e; $(DEMO_RUNS) true

# ---- install -----------------------------------------------------------------
PREFIX ?= /usr/local
prefix ?= $(PREFIX)
libdir ?= $(prefix)/lib
includedir ?= $(prefix)/include
pkgconfigdir ?= $(libdir)/pkgconfig

$(B)/minko.pc: Makefile
	@mkdir -p $(@D)
	printf 'prefix=%s\nlibdir=%s\nincludedir=%s\n\nName: minko\nDescription: portable C99 collision detection ($(PRECISION) precision)\nVersion: %s\nLibs: -L$${libdir} -lminko\nLibs.private: -lm\nCflags: -I$${includedir}\n' \
	  '$(prefix)' '$(libdir)' '$(includedir)' '$(VERSION)' > $@

.PHONY: install uninstall
install: lib $(B)/minko.pc
	install -d $(DESTDIR)$(libdir) $(DESTDIR)$(includedir)/minko $(DESTDIR)$(pkgconfigdir)
	install -m 644 $(STATIC_LIB) $(DESTDIR)$(libdir)/
	install -m 755 $(SHARED_LIB) $(DESTDIR)$(libdir)/
	ln -sf libminko.so.$(VERSION) $(DESTDIR)$(libdir)/$(SONAME)
	ln -sf $(SONAME) $(DESTDIR)$(libdir)/libminko.so
	install -m 644 include/minko/*.h $(CONFIG_H) $(DESTDIR)$(includedir)/minko/
	install -m 644 $(B)/minko.pc $(DESTDIR)$(pkgconfigdir)/
uninstall:
	rm -f $(DESTDIR)$(libdir)/libminko.a $(DESTDIR)$(libdir)/libminko.so.$(VERSION) \
	      $(DESTDIR)$(libdir)/$(SONAME) $(DESTDIR)$(libdir)/libminko.so $(DESTDIR)$(pkgconfigdir)/minko.pc
	rm -rf $(DESTDIR)$(includedir)/minko

.PHONY: clean
clean:
	rm -rf build
