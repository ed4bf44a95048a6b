/* clip_order.c: see clip_order.h. */
#include "clip_order.h"

static int position(const unsigned char *list, int f)
{
    int i = 0;
    while (i < 4 && list[i] != f) ++i;
    return i;
}

int mk_test_clip_rank(int face, int fi, mk_feature fref, mk_feature finc)
{
    int k = face / 2, ku = (k + 1) % 3, kv = (k + 2) % 3;
    if (MK_FEATURE_TYPE(fref) == MK_FEATURE_VERTEX && MK_FEATURE_TYPE(finc) == MK_FEATURE_FACE) {
        int c = MK_FEATURE_GET_INDEX(fref), su = c >> ku & 1, sv = c >> kv & 1;
        return su ? (sv ? 0 : 3) : (sv ? 1 : 2);
    }
    if (MK_FEATURE_TYPE(fref) == MK_FEATURE_EDGE && MK_FEATURE_TYPE(finc) == MK_FEATURE_EDGE) {
        /* Edge e runs along axis e / 4; e's low bits are the corner bits of
         * the other two axes, lower axis first (minko/manifold.h). */
        int e = MK_FEATURE_GET_INDEX(fref), axis = e / 4, lo = axis == 0 ? 1 : 0, hi = axis == 2 ? 1 : 2;
        int bits = (e & 1) << lo | ((e >> 1) & 1) << hi;
        int s = axis == kv ? (bits >> ku & 1 ? 0 : 2) : (bits >> kv & 1 ? 1 : 3);
        return 4 + 4 * position(mk_box_face_edge_[fi], MK_FEATURE_GET_INDEX(finc)) + s;
    }
    if (fref == MK_FEATURE(MK_FEATURE_FACE, face) && MK_FEATURE_TYPE(finc) == MK_FEATURE_VERTEX)
        return 20 + position(mk_box_face_corner_[fi], MK_FEATURE_GET_INDEX(finc));
    return 24;
}

void mk_test_clip_sort(mk_mf *m, int face, int fi, int ref_is_a)
{
    int i, j, r[MK_MF_MAX];
    for (i = 0; i < m->count; ++i) {
        mk_mf_point p = m->p[i];
        mk_feature fa = MK_FEATURE_PAIR_A(p.features), fb = MK_FEATURE_PAIR_B(p.features);
        int ri = ref_is_a ? mk_test_clip_rank(face, fi, fa, fb) : mk_test_clip_rank(face, fi, fb, fa);
        for (j = i; j > 0 && r[j - 1] > ri; --j) r[j] = r[j - 1], m->p[j] = m->p[j - 1];
        r[j] = ri, m->p[j] = p;
    }
}
