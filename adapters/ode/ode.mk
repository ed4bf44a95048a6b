# adapters/ode/ode.mk: the ODE adapter (libminko_ode), its tests and the
# README example (issue 7).
# ODE is double precision; the adapter is
# built in every variant (double, single, sanitizers) and converts between
# dReal and mk_real. pkg-config runs lazily, after `deps`.
ODE_CFLAGS = $(shell $(PKG_CONFIG) --cflags ode)
ODE_LIBS = $(shell $(PKG_CONFIG) --libs ode)

ODE_LIB_SRCS := $(filter-out adapters/ode/test_%.c,$(wildcard adapters/ode/*.c))
ODE_LIB_OBJS := $(ODE_LIB_SRCS:adapters/ode/%.c=$(B)/adapters/ode/%.o)
ODE_LIB := $(B)/libminko_ode.a

$(B)/adapters/ode/%.o: adapters/ode/%.c $(CONFIG_H)
	@mkdir -p $(@D)
	$(say) CC $@
	$(Q)$(CC) -std=c99 -pedantic $(WARN) $(FP) $(INC) -Iadapters/ode $(ODE_CFLAGS) $(CFLAGS) -MMD -MP -c $< -o $@

$(ODE_LIB): $(ODE_LIB_OBJS)
	$(say) AR $@
	$(Q)rm -f $@
	$(Q)$(AR) rcs $@ $^

$(B)/adapters/ode/test_ode_adapter: adapters/ode/test_ode_adapter.c $(ODE_LIB) $(STATIC_LIB) $(TSUP_OBJS)
	@mkdir -p $(@D)
	$(say) CCLD $@
	$(Q)$(CC) $(APP_CFLAGS) -Itests -Iadapters/ode $(CHECK_CFLAGS) $(ODE_CFLAGS) -MMD -MP $< $(TSUP_OBJS) $(ODE_LIB) $(STATIC_LIB) $(LDSAN) $(LDFLAGS) $(CHECK_LIBS) $(ODE_LIBS) -lm -o $@

-include $(ODE_LIB_OBJS:.o=.d) $(B)/adapters/ode/test_ode_adapter.d
CHECK_BINS += $(B)/adapters/ode/test_ode_adapter

# The README's ODE example, extracted from its "## ODE" section, compiled
# (strict C99) and run by `make check` in every variant.
$(B)/readme/ode_example: README.md $(ODE_LIB) $(STATIC_LIB)
	@mkdir -p $(@D)
	$(say) CCLD $@
	$(Q)awk '/^## ODE/{s=1} s && /^```c/{f=1; next} f && /^```/{exit} f' README.md > $(B)/readme/ode_example.c
	$(Q)$(CC) -std=c99 -pedantic $(WARN) $(FP) $(INC) -Iadapters/ode $(ODE_CFLAGS) $(CFLAGS) $(B)/readme/ode_example.c $(ODE_LIB) $(STATIC_LIB) $(LDSAN) $(LDFLAGS) $(ODE_LIBS) -lm -o $@
CHECK_BINS += $(B)/readme/ode_example
