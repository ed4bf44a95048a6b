/* alloc.c: the default allocator and the check of a caller's (see alloc.h). */
#include <stdlib.h>

#include "alloc.h"

static void *default_alloc(void *ctx, size_t size, size_t align)
{
    (void)ctx;
    (void)align; /* malloc's alignment covers every type in Minko's blocks */
    return malloc(size);
}

static void default_free(void *ctx, void *ptr, size_t size)
{
    (void)ctx;
    (void)size;
    free(ptr);
}

mk_status mk_alloc_resolve_(const mk_allocator *in, mk_allocator *out)
{
    if (in) {
        if (!in->alloc || !in->free) return MK_ERR_NULL;
        *out = *in;
        return MK_OK;
    }
    out->alloc = default_alloc;
    out->free = default_free;
    out->ctx = NULL;
    return MK_OK;
}
