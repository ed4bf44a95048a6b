# demos/bench_toi: time of impact against Bullet (btContinuousConvexCollision,
# btGjkConvexCast) and FCL 0.7 (continuousCollide: naive sampling, conservative
# advancement), JSON Lines suite "toi". BULLET_CFLAGS / BULLET_LIBS come from
# adapters/bullet/bullet.mk; the reference is the oracle of tests/support.
FCL_CFLAGS = $(patsubst -I%,-isystem %,$(shell $(PKG_CONFIG) --cflags fcl))
FCL_LIBS = $(shell $(PKG_CONFIG) --libs fcl)

$(B)/demos/bench_toi: demos/bench_toi.cpp $(B)/tests/support/oracle.o $(STATIC_LIB)
	@mkdir -p $(@D)
	$(say) CXXLD $@
	$(Q)$(CXX) $(APP_CXXFLAGS) -Itests $(BULLET_CFLAGS) $(FCL_CFLAGS) -MMD -MP $< $(B)/tests/support/oracle.o $(STATIC_LIB) $(LDSAN) $(LDFLAGS) $(BULLET_LIBS) $(FCL_LIBS) -lm -o $@

-include $(B)/demos/bench_toi.d
DEMO_BINS += $(B)/demos/bench_toi
BENCH_RUNS += $(B)/demos/bench_toi --json $(BENCH_DIR)/toi.jsonl
DEMO_RUNS += $(B)/demos/bench_toi --quick --json $(BENCH_DIR)/toi_quick.jsonl
