// An orthonormal basis (t, b, n) around a unit normal (Duff et al. 2017). Composed into the paraboloid
// depth pass and into the lookup, so a map and its lookup agree.
fn vpl_basis(n: vec3<f32>) -> mat3x3<f32> {
    let sign = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    let t = vec3<f32>(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    let bt = vec3<f32>(b, sign + n.y * n.y * a, -n.y);
    return mat3x3<f32>(t, bt, n);
}
