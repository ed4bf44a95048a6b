# demos/solver_demo.mk (issue 4): the reference sequential-impulse solver that
# measures the contact cache (C, Minko only), and the box-box manifold
# benchmark against Bullet's btBoxBoxDetector / btBoxBoxCollisionAlgorithm and
# ODE's dBoxBox (C++; BULLET_* from adapters/bullet/bullet.mk, ODE_* from
# adapters/ode/ode.mk; the exact depths come from tests/support/oracle.c).
$(B)/demos/solver_demo: demos/solver_demo.c $(STATIC_LIB)
	@mkdir -p $(@D)
	$(say) CCLD $@
	$(Q)$(CC) $(APP_CFLAGS) -MMD -MP $< $(STATIC_LIB) $(LDSAN) $(LDFLAGS) -lm -o $@

$(B)/demos/bench_contacts: demos/bench_contacts.cpp $(B)/tests/support/oracle.o $(STATIC_LIB)
	@mkdir -p $(@D)
	$(say) CXXLD $@
	$(Q)$(CXX) $(APP_CXXFLAGS) -Itests $(BULLET_CFLAGS) $(ODE_CFLAGS) -MMD -MP $< $(B)/tests/support/oracle.o $(STATIC_LIB) $(LDSAN) $(LDFLAGS) $(BULLET_LIBS) $(ODE_LIBS) -lm -o $@

-include $(B)/demos/solver_demo.d $(B)/demos/bench_contacts.d
DEMO_BINS += $(B)/demos/solver_demo $(B)/demos/bench_contacts
BENCH_RUNS += $(call mk_run,$(B)/demos/solver_demo --json $(BENCH_DIR)/contacts_solver.jsonl)
BENCH_RUNS += $(call mk_run,$(B)/demos/bench_contacts --json $(BENCH_DIR)/contacts_box_box.jsonl)
DEMO_RUNS += $(call mk_run,$(B)/demos/solver_demo --quick --json $(BENCH_DIR)/contacts_solver_quick.jsonl)
DEMO_RUNS += $(call mk_run,$(B)/demos/bench_contacts --quick --json $(BENCH_DIR)/contacts_box_box_quick.jsonl)
