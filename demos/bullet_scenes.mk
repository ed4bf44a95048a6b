# demos/bullet_scenes: Bullet's benchmark scenes and stiff / extreme cases,
# headless, every backend in one process run (JSON Lines, suite "bullet").
# BULLET_CFLAGS / BULLET_LIBS / BULLET_TAG come from adapters/bullet/bullet.mk.
$(B)/demos/bullet_scenes: demos/bullet_scenes.cpp $(STATIC_LIB)
	@mkdir -p $(@D)
	$(say) CXXLD $@
	$(Q)$(CXX) $(APP_CXXFLAGS) $(BULLET_CFLAGS) -MMD -MP $< $(STATIC_LIB) $(LDSAN) $(LDFLAGS) $(BULLET_LIBS) -lm -o $@

-include $(B)/demos/bullet_scenes.d
DEMO_BINS += $(B)/demos/bullet_scenes
BENCH_RUNS += $(B)/demos/bullet_scenes --json $(BENCH_DIR)/bullet_scenes.jsonl
DEMO_RUNS += $(B)/demos/bullet_scenes --quick --json $(BENCH_DIR)/bullet_scenes_quick.jsonl
