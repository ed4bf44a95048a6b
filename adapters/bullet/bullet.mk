# adapters/bullet: Bullet 3.24 glue, built against the Bullet build whose
# precision matches Minko's: `bullet-float64` (BT_USE_DOUBLE_PRECISION) with the
# double library, `bullet` (float) with PRECISION=single. Bullet's headers are
# included as system headers so -Wextra -Werror judges only our code.
ifeq ($(PRECISION),single)
  BULLET_PC := bullet
  BULLET_TAG := bullet_f32
else
  BULLET_PC := bullet-float64
  BULLET_TAG := bullet_f64
endif
BULLET_CFLAGS = $(patsubst -I%,-isystem %,$(shell $(PKG_CONFIG) --cflags $(BULLET_PC)))
BULLET_LIBS = $(shell $(PKG_CONFIG) --libs $(BULLET_PC))

# libminko_bullet: the adapter library, one per build variant.
MKB_SRCS := $(filter-out adapters/bullet/test_%.cpp,$(wildcard adapters/bullet/*.cpp))
MKB_OBJS := $(MKB_SRCS:adapters/bullet/%.cpp=$(B)/adapters/bullet/%.o)
MKB_LIB := $(B)/libminko_bullet.a
MKB_CXXFLAGS = $(APP_CXXFLAGS) -Iadapters/bullet $(BULLET_CFLAGS)

$(B)/adapters/bullet/%.o: adapters/bullet/%.cpp $(CONFIG_H)
	@mkdir -p $(@D)
	$(say) CXX $@
	$(Q)$(CXX) $(MKB_CXXFLAGS) -MMD -MP -c $< -o $@

$(MKB_LIB): $(MKB_OBJS)
	$(say) AR $@
	$(Q)rm -f $@
	$(Q)$(AR) rcs $@ $^

# The adapter's Check suite, run by `make check` in every variant.
$(B)/adapters/bullet/test_minko_bullet: adapters/bullet/test_minko_bullet.cpp $(MKB_LIB) $(STATIC_LIB) $(TSUP_OBJS)
	@mkdir -p $(@D)
	$(say) CXXLD $@
	$(Q)$(CXX) $(MKB_CXXFLAGS) -Itests $(CHECK_CFLAGS) -MMD -MP $< $(TSUP_OBJS) $(MKB_LIB) $(STATIC_LIB) $(LDSAN) $(LDFLAGS) $(BULLET_LIBS) $(CHECK_LIBS) -lm -o $@

-include $(MKB_OBJS:.o=.d) $(B)/adapters/bullet/test_minko_bullet.d
CHECK_BINS += $(B)/adapters/bullet/test_minko_bullet

# The Bullet example in README.md (the first C++ block after "## Bullet") must
# compile and run, in every build.
$(B)/adapters/bullet/readme_example: README.md $(MKB_LIB) $(STATIC_LIB)
	@mkdir -p $(@D)
	$(say) CXXLD $@
	$(Q)awk '/^## Bullet/{s=1} s && /^```cpp/{f=1; next} f && /^```/{exit} f' README.md > $(B)/adapters/bullet/readme_example.cpp
	$(Q)$(CXX) $(MKB_CXXFLAGS) $(B)/adapters/bullet/readme_example.cpp $(MKB_LIB) $(STATIC_LIB) $(LDSAN) $(LDFLAGS) $(BULLET_LIBS) -lm -o $@
CHECK_BINS += $(B)/adapters/bullet/readme_example
