"""usd-core's skinned points of a UsdSkel-bound mesh at given times, as JSON on stdout: the
reference of tests/it/anim.rs (`UsdSkel.Cache`, `SkinningQuery.ComputeSkinnedPoints`, in
skeleton space). Usage: python3 usd_skin_reference.py FILE.usda MESH_PRIM TIME...
Exits with status 3 when `pxr` (PyPI usd-core) is missing."""
import json
import sys

try:
    from pxr import Usd, UsdSkel
except ImportError:
    sys.exit(3)

path, prim, times = sys.argv[1], sys.argv[2], [float(t) for t in sys.argv[3:]]
stage = Usd.Stage.Open(path)
mesh = stage.GetPrimAtPath(prim)
root = UsdSkel.Root.Find(mesh)
cache = UsdSkel.Cache()
cache.Populate(root, Usd.PrimDefaultPredicate)
query = cache.GetSkinningQuery(mesh)
skel_query = cache.GetSkelQuery(UsdSkel.BindingAPI(mesh).GetInheritedSkeleton())
out = []
for t in times:
    xforms = skel_query.ComputeSkinningTransforms(t)
    points = mesh.GetAttribute("points").Get(t)
    assert query.ComputeSkinnedPoints(xforms, points, t)
    out.append([[float(c) for c in p] for p in points])
print(json.dumps(out))
