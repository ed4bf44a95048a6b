# demos/bench_sat: the separating-axis test against Minko's GJK/EPA on box and
# hull pairs (suite "sat"); references from tests/support/oracle.c.
$(B)/demos/bench_sat: demos/bench_sat.c $(B)/tests/support/oracle.o $(STATIC_LIB)
	@mkdir -p $(@D)
	$(say) CCLD $@
	$(Q)$(CC) $(APP_CFLAGS) -Itests -MMD -MP $< $(B)/tests/support/oracle.o $(STATIC_LIB) $(LDSAN) $(LDFLAGS) -lm -o $@

-include $(B)/demos/bench_sat.d
DEMO_BINS += $(B)/demos/bench_sat
BENCH_RUNS += $(call mk_run,$(B)/demos/bench_sat --json $(BENCH_DIR)/sat.jsonl)

# A tiny run in `make check` (non-sanitizer builds) so the benchmark cannot rot.
ifeq ($(SAN),0)
$(B)/tests/bench_sat_smoke: $(B)/demos/bench_sat
	@mkdir -p $(@D)
	@printf '#!/bin/sh\nset -e\n%s --quick --n 3 --reps 1 >/dev/null\necho "bench_sat smoke: ok"\n' $< > $@
	@chmod +x $@
CHECK_BINS += $(B)/tests/bench_sat_smoke
endif
