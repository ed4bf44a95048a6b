# adapters/ode/ode.mk: the ODE adapter (libminko_ode) and its tests (issue 7).
# ODE is double precision here; pkg-config is evaluated lazily, after `deps`.
ODE_CFLAGS = $(shell $(PKG_CONFIG) --cflags ode)
ODE_LIBS = $(shell $(PKG_CONFIG) --libs ode)
