"""The skinned `Mesh "Tube"` prim both skinning test assets end with (make_skin_cylinder.py,
make_twist_cylinder.py): faces, points, the skeleton binding and `influences` joint indices
and weights per vertex, optionally a geomBindTransform; closes the SkelRoot."""


def tube_mesh(w, counts, faces, points, idx, wts, influences, geom_bind=None):
    """Appends the prim's text to `w`; `points` is the points list already formatted."""
    w('    def Mesh "Tube" (\n        prepend apiSchemas = ["SkelBindingAPI"]\n    )\n    {\n')
    w("        int[] faceVertexCounts = [%s]\n" % ", ".join(map(str, counts)))
    w("        int[] faceVertexIndices = [%s]\n" % ", ".join(map(str, faces)))
    w("        point3f[] points = [%s]\n" % points)
    w("        rel skel:skeleton = </Model/Skel>\n")
    primvar = '(\n            elementSize = %d\n            interpolation = "vertex"\n        )\n' % influences
    w("        int[] primvars:skel:jointIndices = [%s] %s" % (", ".join(map(str, idx)), primvar))
    w("        float[] primvars:skel:jointWeights = [%s] %s" % (", ".join("%.9g" % x for x in wts), primvar))
    if geom_bind:
        w("        matrix4d primvars:skel:geomBindTransform = %s\n" % geom_bind)
    w("    }\n}\n")
