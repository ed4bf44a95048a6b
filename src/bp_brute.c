/* bp_brute.c: the O(n^2) reference broadphase. Every update tests every pair
 * of live proxies against each other; it is the oracle the tests hold SAP
 * and the grid to, so it stays as plain as possible. */
#include "broadphase_internal.h"

static int in_structure(const mk_bp *bp, int s)
{
    return (bp->flags[s] & (MK_PF_ALIVE | MK_PF_DYING)) == MK_PF_ALIVE;
}

mk_status mk_brute_update_(mk_bp *bp)
{
    int i, j;
    mk_status st = MK_OK;
    mk_bp_commit_(bp);
    mk_pairs_full_begin_(bp);
    for (i = 0; i < bp->hi_slot && st == MK_OK; ++i) {
        if (!in_structure(bp, i)) continue;
        for (j = i + 1; j < bp->hi_slot && st == MK_OK; ++j) {
            if (!in_structure(bp, j) || mk_bp_both_static_(bp, (uint32_t)i, (uint32_t)j)) continue;
            if (mk_bp_overlap_(&bp->box[i], &bp->box[j])) st = mk_pairs_full_add_(bp, (uint32_t)i, (uint32_t)j);
        }
    }
    if (st != MK_OK) { bp->pairs.full = 0; return st; }
    mk_pairs_full_end_(bp);
    bp->rebuild = 0;
    return MK_OK;
}
