# demos/bench_broadphase: Minko's broadphases against Bullet, ODE and FCL on
# the scenes of issue 3, one process run (JSON Lines, suite "broad").
# BULLET_* come from adapters/bullet/bullet.mk, ODE_* from adapters/ode/ode.mk.
# Third-party headers are system headers so -Werror judges only our code.
BB_FCL_CFLAGS = $(patsubst -I%,-isystem %,$(shell $(PKG_CONFIG) --cflags fcl))
BB_FCL_LIBS = $(shell $(PKG_CONFIG) --libs fcl)

$(B)/demos/bench_broadphase_minko.o: demos/bench_broadphase_minko.c $(CONFIG_H)
	@mkdir -p $(@D)
	$(say) CC $@
	$(Q)$(CC) $(APP_CFLAGS) -MMD -MP -c $< -o $@

$(B)/demos/bench_broadphase: demos/bench_broadphase.cc $(B)/demos/bench_broadphase_minko.o $(STATIC_LIB)
	@mkdir -p $(@D)
	$(say) CXXLD $@
	$(Q)$(CXX) $(APP_CXXFLAGS) $(BULLET_CFLAGS) $(patsubst -I%,-isystem %,$(ODE_CFLAGS)) $(BB_FCL_CFLAGS) -MMD -MP $< \
	  $(B)/demos/bench_broadphase_minko.o $(STATIC_LIB) $(LDSAN) $(LDFLAGS) $(BULLET_LIBS) $(ODE_LIBS) $(BB_FCL_LIBS) -lm -o $@

-include $(B)/demos/bench_broadphase.d $(B)/demos/bench_broadphase_minko.d
DEMO_BINS += $(B)/demos/bench_broadphase
BENCH_RUNS += $(call mk_run,$(B)/demos/bench_broadphase --json $(BENCH_DIR)/broad.jsonl)
DEMO_RUNS += $(call mk_run,$(B)/demos/bench_broadphase --quick --json $(BENCH_DIR)/broad_quick.jsonl)
