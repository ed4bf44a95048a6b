# demos/bench_toi: time of impact against Bullet (btContinuousConvexCollision,
# btGjkConvexCast) and FCL 0.7 (continuousCollide: naive sampling, conservative
# advancement), JSON Lines suite "toi". BULLET_CFLAGS / BULLET_LIBS come from
# adapters/bullet/bullet.mk; the reference is the oracle of tests/support.
FCL_CFLAGS = $(patsubst -I%,-isystem %,$(shell $(PKG_CONFIG) --cflags fcl))
FCL_LIBS = $(shell $(PKG_CONFIG) --libs fcl)

# The bilateral advancement prototype runs on the library's internal GJK
# (src/gjk.h), linked statically like mk_toi itself.
$(B)/demos/bench_toi_bilateral.o: demos/bench_toi_bilateral.c $(CONFIG_H)
	@mkdir -p $(@D)
	$(say) CC $@
	$(Q)$(CC) $(APP_CFLAGS) -MMD -MP -c $< -o $@

$(B)/demos/bench_toi: demos/bench_toi.cpp $(B)/demos/bench_toi_bilateral.o $(B)/tests/support/oracle.o $(STATIC_LIB)
	@mkdir -p $(@D)
	$(say) CXXLD $@
	$(Q)$(CXX) $(APP_CXXFLAGS) -Itests -Idemos $(BULLET_CFLAGS) $(FCL_CFLAGS) -MMD -MP $< $(B)/demos/bench_toi_bilateral.o $(B)/tests/support/oracle.o $(STATIC_LIB) $(LDSAN) $(LDFLAGS) $(BULLET_LIBS) $(FCL_LIBS) -lm -o $@

-include $(B)/demos/bench_toi.d $(B)/demos/bench_toi_bilateral.d
DEMO_BINS += $(B)/demos/bench_toi
BENCH_RUNS += $(call mk_run,$(B)/demos/bench_toi --json $(BENCH_DIR)/toi.jsonl)
DEMO_RUNS += $(call mk_run,$(B)/demos/bench_toi --quick --json $(BENCH_DIR)/toi_quick.jsonl)

# A few cases of every family and backend in `make check`, so the demo cannot rot.
ifeq ($(SAN),0)
$(B)/tests/bench_toi_smoke: $(B)/demos/bench_toi
	@mkdir -p $(@D)
	@printf '#!/bin/sh\nset -e\n%s --quick --cases 3 >/dev/null\necho "bench_toi smoke: ok"\n' $< > $@
	@chmod +x $@
CHECK_BINS += $(B)/tests/bench_toi_smoke
endif
