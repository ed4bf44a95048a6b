/* alloc.h (internal): the one place where a caller's optional allocator
 * becomes a usable one, so every module validates it alike and falls back
 * to the same malloc/free. */
#ifndef MINKO_SRC_ALLOC_H
#define MINKO_SRC_ALLOC_H
#include "minko/base.h"

/* NULL `in` gives malloc/free (malloc's alignment covers every type Minko
 * allocates); an allocator missing either function is MK_ERR_NULL. */
mk_status mk_alloc_resolve_(const mk_allocator *in, mk_allocator *out);

#endif
