# demos/bullet_scenes: Bullet's benchmark scenes and stiff / extreme cases,
# headless, every backend in one process run (JSON Lines, suite "bullet").
# MKB_LIB, MKB_CXXFLAGS, BULLET_LIBS come from adapters/bullet/bullet.mk.
# The penetration referee uses the tests' long double oracle (no Check inside).
$(B)/demos/bullet_scenes: demos/bullet_scenes.cpp $(MKB_LIB) $(STATIC_LIB) $(B)/tests/support/oracle.o
	@mkdir -p $(@D)
	$(say) CXXLD $@
	$(Q)$(CXX) $(MKB_CXXFLAGS) -Itests -MMD -MP $< $(B)/tests/support/oracle.o $(MKB_LIB) $(STATIC_LIB) $(LDSAN) $(LDFLAGS) $(BULLET_LIBS) -lm -o $@

-include $(B)/demos/bullet_scenes.d
DEMO_BINS += $(B)/demos/bullet_scenes
BENCH_RUNS += $(call mk_run,$(B)/demos/bullet_scenes --json $(BENCH_DIR)/bullet_scenes.jsonl)
DEMO_RUNS += $(call mk_run,$(B)/demos/bullet_scenes --quick --json $(BENCH_DIR)/bullet_scenes_quick.jsonl)
