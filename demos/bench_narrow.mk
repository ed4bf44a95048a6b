# demos/bench_narrow.mk: the narrowphase benchmark of issue 2 §5 (suite "narrow").
# One binary per precision: build/demos/bench_narrow (Minko double, libccd,
# Bullet double, ODE) and build/single/demos/bench_narrow (Minko float, Bullet
# float); the second appends to the first's JSON file. BULLET_* and ODE_* come
# from adapters/bullet/bullet.mk and adapters/ode/ode.mk. The cases and their
# exact references are tests/support/cases.c and oracle.c.
BN_SUPPORT := $(B)/tests/support/oracle.o $(B)/tests/support/cases.o
ifeq ($(PRECISION),single)
  BN_LIBS = $(BULLET_LIBS)
else
  BN_LIBS = $(BULLET_LIBS) $(shell $(PKG_CONFIG) --libs ccd) $(ODE_LIBS)
endif

$(B)/demos/bench_narrow: demos/bench_narrow.cc $(BN_SUPPORT) $(STATIC_LIB)
	@mkdir -p $(@D)
	$(say) CXXLD $@
	$(Q)$(CXX) $(APP_CXXFLAGS) -Itests $(BULLET_CFLAGS) $(ODE_CFLAGS) -MMD -MP $< $(BN_SUPPORT) $(STATIC_LIB) $(LDSAN) $(LDFLAGS) $(BN_LIBS) -lm -o $@

-include $(B)/demos/bench_narrow.d
DEMO_BINS += $(B)/demos/bench_narrow
BENCH_RUNS += $(call mk_run,$(B)/demos/bench_narrow --json $(BENCH_DIR)/narrow.jsonl)
DEMO_RUNS += $(call mk_run,$(B)/demos/bench_narrow --quick)

# The float companion, built by a sub-make with PRECISION=single.
ifeq ($(PRECISION)-$(SAN),double-0)
BN_F32 := build/single/demos/bench_narrow
.PHONY: bench-narrow-f32-always
$(BN_F32): bench-narrow-f32-always
	$(Q)$(MAKE) --no-print-directory PRECISION=single SAN=0 $@
DEMO_BINS += $(BN_F32)
BENCH_RUNS += $(call mk_run,$(BN_F32) --json $(BENCH_DIR)/narrow.jsonl --append)
DEMO_RUNS += $(call mk_run,$(BN_F32) --quick)
endif

# make check runs a smoke test of the benchmark (non-sanitizer builds): every
# backend keeps its sign conventions (--selftest) and a tiny run completes, so
# `make demo` cannot rot unnoticed.
ifeq ($(SAN),0)
$(B)/tests/bench_narrow_smoke: $(B)/demos/bench_narrow
	@mkdir -p $(@D)
	@printf '#!/bin/sh\nset -e\n%s --selftest >/dev/null\n%s --quick --n 2 --reps 1 >/dev/null\necho "bench_narrow smoke: ok"\n' $< $< > $@
	@chmod +x $@
CHECK_BINS += $(B)/tests/bench_narrow_smoke
endif
