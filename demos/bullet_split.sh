#!/bin/sh
# demos/bullet_split.sh: the collision phase of one bullet_scenes callgrind
# run, split per component (inclusive instruction counts, millions), for
# Minko's adapter and Bullet's native pipeline alike. Rows a run does not
# have are left out; "other" rows are the parent less its named children
# (dispatch: pair callback, wrappers, algorithm lookup; processCollision:
# the adapter's own glue, shape checks -- refresh_map of an unchanged box is
# inline there --, result bookkeeping).
#
#   valgrind --tool=callgrind --toggle-collect='btCollisionWorld::performDiscreteCollisionDetection()' \
#       --callgrind-out-file=/tmp/x.cg build/demos/bullet_scenes --scene 1000_stack --steps 300 \
#       --backend minko --no-native --no-referee        # or: --backend native
#   demos/bullet_split.sh /tmp/x.cg
set -e
[ -r "$1" ] || { echo "usage: $0 CALLGRIND_OUT" >&2; exit 2; }
# Run away from the sources: found sources change how inlined code is
# grouped per file:function entry.
f=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
(cd / && callgrind_annotate --inclusive=yes --threshold=100 "$f" 2>/dev/null) | awk -v q="'" '
function pick(pat,   i) { for (i = 1; i <= n; i++) if (index(name[i], pat)) return ir[i]; return -1 }
function row(label, v) { if (v >= 0) printf "%-40s %9.1f M\n", label, v / 1e6 }
function sum(a, b) { return (a > 0 ? a : 0) + (b > 0 ? b : 0) }
/^ *[0-9][0-9,]* / { v = $1; gsub(",", "", v); n++; ir[n] = v + 0; name[n] = $0 }
END {
  total = pick("PROGRAM TOTALS")
  aabbs = pick("btCollisionWorld::updateAabbs()")
  getaabb = pick("btBoxShape::getAabb")
  setm = pick("mkb::Broadphase::setAabb"); setd = pick("btDbvtBroadphase::setAabb")
  pairs = pick("btCollisionWorld::computeOverlappingPairs()")
  bpu = pick("broadphase.c:mk_bp_update"); dbvtc = pick("btDbvtBroadphase::calculateOverlappingPairs")
  disp = pick("btCollisionDispatcher::dispatchAllCollisionPairs")
  order = pick("PairCache::update_order"); qs = pick("0x000000000004e000" q "2")
  near = pick("btCollisionDispatcher::defaultNearCallback")
  needs = pick("btCollisionDispatcher::needsCollision")
  find = pick("btCollisionDispatcher::findAlgorithm")
  mpc = pick("mkb::(anonymous namespace)::Algorithm::processCollision")
  bpc = pick("btBoxBoxCollisionAlgorithm::processCollision")
  row("collision phase", total)
  row("updateAabbs", aabbs)
  row("  btBoxShape::getAabb", getaabb)
  row("  setAabb (Minko)", setm)
  row("  setAabb (Dbvt: tree update, new pairs)", setd)
  row("computeOverlappingPairs", pairs)
  row("  mk_bp_update", bpu)
  row("  Dbvt calculateOverlappingPairs", dbvtc)
  row("dispatchAllCollisionPairs", disp)
  row("  pair order (Minko PairCache)", order)
  row("  pair order (Bullet quicksort)", qs)
  row("  defaultNearCallback", near)
  row("    needsCollision", needs)
  row("    findAlgorithm (new pairs)", find)
  if (mpc >= 0) {
    row("    Minko processCollision", mpc)
    c = pick("manifold.c:mk_collide_pose"); row("      mk_collide_pose", c)
    w = pick("CollisionConfiguration::world_poses"); row("      world_poses", w)
    r = pick("mkb::detail::refresh_changed"); row("      refresh_map (out of line: changed shapes)", r)
    f = pick("mkb::(anonymous namespace)::farther"); row("      apart (farther)", f)
    wc = pick("mkb::write_contacts(btManifoldResult"); row("      write_contacts", wc)
    rc = pick("mkb::refresh_contacts(btManifoldResult*, bool) ["); row("      refresh_contacts", rc)
    tb = pick("mkb::(anonymous namespace)::to_bullet"); row("      to_bullet", tb)
    row("      other (glue, manifold setup)", mpc - sum(c, w) - sum(r, f) - sum(wc, rc) - sum(tb, 0))
    row("    other near callback (wrappers, result)", near - mpc - sum(needs, find))
  }
  if (bpc >= 0) {
    row("    btBoxBoxCollisionAlgorithm", bpc)
    d = pick("btBoxBoxDetector::getClosestPoints"); row("      btBoxBoxDetector (dBoxBox2)", d)
    a = pick("btManifoldResult::addContactPoint"); row("        addContactPoint", a)
    rc = pick("btPersistentManifold::refreshContactPoints"); row("      refreshContactPoints", rc)
    row("      other", bpc - sum(d, rc))
    row("    other near callback (wrappers, result)", near - bpc - sum(needs, find))
  }
  if (near >= 0) row("  other dispatch (pair walk, callback)", disp - near - sum(order, qs))
  row("other (collision phase)", total - sum(aabbs, pairs) - sum(disp, 0))
}'
