# demos/ode_scenes.mk: ODE scenes side by side, native collision against Minko (issue 7).
$(B)/demos/ode_scenes: demos/ode_scenes.c $(B)/tests/support/oracle.o $(ODE_LIB) $(STATIC_LIB)
	@mkdir -p $(@D)
	$(say) CCLD $@
	$(Q)$(CC) $(APP_CFLAGS) -Itests -Iadapters/ode $(ODE_CFLAGS) -MMD -MP $< $(B)/tests/support/oracle.o $(ODE_LIB) $(STATIC_LIB) $(LDSAN) $(LDFLAGS) $(ODE_LIBS) -lm -o $@

-include $(B)/demos/ode_scenes.d
DEMO_BINS += $(B)/demos/ode_scenes
BENCH_RUNS += $(call mk_run,$(B)/demos/ode_scenes --json $(BENCH_DIR)/ode.jsonl)
DEMO_RUNS += $(call mk_run,$(B)/demos/ode_scenes --quick)
