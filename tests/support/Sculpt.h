// Shorthands for building test volumes with the CSG kernel.
#pragma once

#include "sculpt/Brush.h"
#include "sculpt/Csg.h"
#include "vdb_hermite/Volume.h"

namespace vdbclay::test {

inline Primitive sphere(double r)
{
    Primitive p;
    p.shape = Shape::Sphere;
    p.radius = r;
    return p;
}
inline Primitive box(const Vec3d& halfExtents, double rounding = 0.0)
{
    Primitive p;
    p.shape = Shape::Box;
    p.size = halfExtents;
    p.rounding = rounding;
    return p;
}
inline Primitive cylinder(double r, double height)
{
    Primitive p;
    p.shape = Shape::Cylinder;
    p.radius = r;
    p.height = height;
    return p;
}
inline Primitive capsule(double r, double length)
{
    Primitive p;
    p.shape = Shape::Capsule;
    p.radius = r;
    p.length = length;
    return p;
}
inline Primitive torus(double major, double minor)
{
    Primitive p;
    p.shape = Shape::Torus;
    p.radius = major;
    p.minorRadius = minor;
    return p;
}
inline Primitive cone(double r, double height)
{
    Primitive p;
    p.shape = Shape::Cone;
    p.radius = r;
    p.height = height;
    return p;
}
inline Primitive halfSpace(const Vec3d& normal)
{
    Primitive p;
    p.shape = Shape::HalfSpace;
    p.normal = normal;
    return p;
}

inline Placement at(const Vec3d& t, const Vec3d& rotationDegrees = Vec3d(0.0), const Vec3d& scale = Vec3d(1.0))
{
    Placement pl;
    pl.translation = t;
    pl.rotationDegrees = rotationDegrees;
    pl.scale = scale;
    return pl;
}

inline CsgOp op(CsgMode mode, MaterialId material = 1, double strength = 1.0)
{
    CsgOp o;
    o.mode = mode;
    o.material = material;
    o.strength = strength;
    return o;
}

inline EditStats apply(Volume& v, CsgMode mode, const Primitive& p, const Placement& pl, MaterialId material = 1)
{
    return applyCsg(v, Brush(p, pl), op(mode, material));
}

inline MaterialId defineMaterial(Volume& v, const std::string& name, float toughness,
                                 std::array<float, 4> color = {0.5f, 0.5f, 0.5f, 1.0f})
{
    Material m;
    m.name = name;
    m.toughness = toughness;
    m.color = color;
    return v.materials().define(m);
}

/// Spans several 64-voxel bricks on both sides of the origin, with two materials and a solid interior
/// that spans whole bricks at level 0 (uniform bricks) and whole blocks at level 2.
inline Volume multiBrickScene()
{
    Volume v(0.5);
    const MaterialId red = defineMaterial(v, "red", 0.5f);
    apply(v, CsgMode::Add, sphere(70.0), at(Vec3d(3.1, -2.0, 1.0)));
    apply(v, CsgMode::Add, box(Vec3d(20.0, 10.0, 12.0)), at(Vec3d(45.0, 20.0, -10.0), Vec3d(0.0, 30.0, 0.0)), red);
    apply(v, CsgMode::Remove, sphere(12.0), at(Vec3d(-40.0, 0.0, 20.0)));
    return v;
}

} // namespace vdbclay::test
