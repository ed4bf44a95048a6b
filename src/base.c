/* base.c: status strings, version and the precision guard symbol. */
#include "minko/base.h"

/* Defined only for the precision this library was built with; see base.h. */
MK_API const int MK_ABI_SYMBOL = MK_VERSION_MAJOR;

const char *mk_status_str(mk_status s)
{
    switch (s) {
#define MK_STATUS_STR_(code, name, msg) case name: return msg;
        MK_STATUS_LIST(MK_STATUS_STR_)
#undef MK_STATUS_STR_
    default: return "unknown mk_status value";
    }
}

const char *mk_status_name(mk_status s)
{
    switch (s) {
#define MK_STATUS_NAME_(code, name, msg) case name: return #name;
        MK_STATUS_LIST(MK_STATUS_NAME_)
#undef MK_STATUS_NAME_
    default: return "MK_STATUS_UNKNOWN";
    }
}

int mk_version(void) { return MK_VERSION_NUMBER; }

int mk_is_double_precision(void)
{
#if defined(MK_SINGLE)
    return 0;
#else
    return 1;
#endif
}
