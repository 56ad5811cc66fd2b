// Octahedral normal encoding (Cigolle et al., "A Survey of Efficient Representations for
// Independent Unit Vectors", JCGT 2014): a unit vector as two numbers in [-1, 1], so the
// G-buffer stores a normal in one two-channel target.

fn sign_not_zero(v: vec2<f32>) -> vec2<f32> {
    return select(vec2<f32>(-1.0), vec2<f32>(1.0), v >= vec2<f32>(0.0));
}

fn octahedral_encode(n: vec3<f32>) -> vec2<f32> {
    let p = n.xy / (abs(n.x) + abs(n.y) + abs(n.z));
    if (n.z >= 0.0) {
        return p;
    }
    return (1.0 - abs(p.yx)) * sign_not_zero(p);
}

fn octahedral_decode(e: vec2<f32>) -> vec3<f32> {
    var n = vec3<f32>(e, 1.0 - abs(e.x) - abs(e.y));
    if (n.z < 0.0) {
        n = vec3<f32>((1.0 - abs(n.yx)) * sign_not_zero(n.xy), n.z);
    }
    return normalize(n);
}
