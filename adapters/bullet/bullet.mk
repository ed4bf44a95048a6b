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
