// INSM's adaptive mesh (beyond the paper): the quadtree of planar blocks in each tile, the leaves and their
// triangles. Appended to core/src/technique/insm/triangulate.wgsl (its bindings, workgroup variables and
// helpers), which describes the scheme; the CPU twin is core/src/technique/insm/triangulate/adaptive.rs.

// Block `bit` of a tile's planar mask: its origin in the tile and its side, in neighbourhoods.
fn mask_block(bit: u32) -> vec3<u32> {
    if bit == 0u {
        return vec3<u32>(0u, 0u, TILE);
    }
    if bit < 5u {
        return vec3<u32>((bit - 1u) % 2u * 4u, (bit - 1u) / 2u * 4u, 4u);
    }
    return vec3<u32>((bit - 5u) % 4u * 2u, (bit - 5u) / 4u * 2u, 2u);
}

// Block b (origin in the tile, side) is planar: whole, every neighbourhood keeps both triangles (the tile's
// full bits, complete when this runs), every sample within merge_epsilon of the affine function through its
// corners. The twin of `SampledImage::block_planar`.
fn block_planar(b: vec3<u32>) -> bool {
    let o = tile_origin + vec2<i32>(b.xy);
    let s = i32(b.z);
    if any(o + vec2<i32>(s) >= vec2<i32>(i32(params.resolution))) {
        return false;
    }
    for (var j = 0u; j < b.z; j++) {
        for (var i = 0u; i < b.z; i++) {
            let bit = (b.y + j) * TILE + b.x + i;
            if ((atomicLoad(&full_bits[bit / 32u]) >> (bit % 32u)) & 1u) == 0u {
                return false;
            }
        }
    }
    let z00 = z_at(o);
    let z10 = z_at(o + vec2<i32>(s, 0));
    let z01 = z_at(o + vec2<i32>(0, s));
    for (var j = 0; j <= s; j++) {
        for (var i = 0; i <= s; i++) {
            let f = vec2<f32>(f32(i), f32(j)) / f32(s);
            let fit = z00 + (z10 - z00) * f.x + (z01 - z00) * f.y;
            let z = z_at(o + vec2<i32>(i, j));
            // Written so that NaN fails.
            if !(abs(z - fit) < params.merge_epsilon * z) {
                return false;
            }
        }
    }
    return true;
}

// The leaf of the quadtree that holds neighbourhood n of `image`: the largest planar block of its tile's mask
// around it, or n alone, as (origin, side) in neighbourhoods; side 0 outside the image's neighbourhoods. The
// twin of `SampledImage::leaf`.
fn leaf_of(image: u32, n: vec2<i32>) -> vec3<i32> {
    let neighbourhoods = i32(params.resolution) - 1;
    if any(n < vec2<i32>(0)) || any(n >= vec2<i32>(neighbourhoods)) {
        return vec3<i32>(0);
    }
    let t = vec2<u32>(n) / TILE;
    let mask = tiles[tile_index(image, t)].merged;
    let l = vec2<u32>(n) % TILE;
    let bits = vec3<u32>(0u, 1u + l.y / 4u * 2u + l.x / 4u, 5u + l.y / 2u * 4u + l.x / 2u);
    for (var i = 0u; i < 3u; i++) {
        if ((mask >> bits[i]) & 1u) != 0u {
            let b = mask_block(bits[i]);
            return vec3<i32>(vec2<i32>(t * TILE + b.xy), i32(b.z));
        }
    }
    return vec3<i32>(n, 1);
}

// Sample p is a vertex of the adaptive mesh: a corner of the leaf of one of the neighbourhoods around it.
fn is_vertex(image: u32, p: vec2<i32>) -> bool {
    for (var d = 0; d < 4; d++) {
        let leaf = leaf_of(image, p - vec2<i32>(d % 2, d / 2));
        let l = p - leaf.xy;
        if leaf.z > 0 && (l.x == 0 || l.x == leaf.z) && (l.y == 0 || l.y == leaf.z) {
            return true;
        }
    }
    return false;
}

// Boundary point k (0..=s) of side `side` of a block of side s, in fan order: top right to left, left down,
// bottom left to right, right up (block coordinates).
fn side_point(side: u32, k: i32, s: i32) -> vec2<i32> {
    switch side {
        case 0u: { return vec2<i32>(s - k, 0); }
        case 1u: { return vec2<i32>(0, k); }
        case 2u: { return vec2<i32>(k, s); }
        default: { return vec2<i32>(s, s - k); }
    }
}

fn emit(o: u32, a: u32, b: u32, c: u32) {
    indices[o] = a;
    indices[o + 1u] = b;
    indices[o + 2u] = c;
}

// The triangles of merged leaf `leaf` (origin, side; in this tile) of `image` into tile `tile`'s slot: none when
// another map reconstructs all its samples more finely, two when its sides hold no vertex but its corners,
// else a fan from its centre over the vertices of its boundary. The twin of `SampledImage::leaf_triangles`.
fn emit_leaf(image: u32, tile: u32, leaf: vec3<i32>) {
    let o = leaf.xy;
    let s = leaf.z;
    var all_covered = true;
    for (var j = 0; j <= s && all_covered; j++) {
        for (var i = 0; i <= s; i++) {
            if !corner_covered(o + vec2<i32>(i, j)) {
                all_covered = false;
                break;
            }
        }
    }
    if all_covered {
        return;
    }
    // Which boundary points (index side * s + k, at most 4 * TILE = 32: one bit each) are vertices, asked once.
    var vertices_mask = 0u;
    for (var side = 0u; side < 4u; side++) {
        for (var k = 0; k < s; k++) {
            let p = o + side_point(side, k, s);
            if is_vertex(image, p) {
                vertices_mask |= 1u << (side * u32(s) + u32(k));
            }
            // Bounds: every sample of the boundary (a superset of the vertices).
            grow_bounds(p_at(p));
        }
    }
    let n = countOneBits(vertices_mask);
    grow_bounds(p_at(o + vec2<i32>(s / 2)));
    let r = i32(params.resolution);
    let base = i32(image) * r * r;
    let index = base + o.y * r + o.x;
    if n == 4u {
        let slot = atomicAdd(&tri_count, 2u);
        let out = (tile * MAX_TRIS + slot) * 3u;
        emit(out, u32(index), u32(index + s * r), u32(index + s * r + s));
        emit(out + 3u, u32(index + s * r + s), u32(index + s), u32(index));
        return;
    }
    let slot = atomicAdd(&tri_count, n);
    var out = (tile * MAX_TRIS + slot) * 3u;
    let centre = u32(index + (s / 2) * r + s / 2);
    // The first boundary point, the top right corner, is a vertex.
    let first = u32(index + s);
    var previous = first;
    for (var side = 0u; side < 4u; side++) {
        for (var k = select(0, 1, side == 0u); k < s; k++) {
            let l = side_point(side, k, s);
            if ((vertices_mask >> (side * u32(s) + u32(k))) & 1u) != 0u {
                let v = u32(index + l.y * r + l.x);
                emit(out, centre, previous, v);
                out += 3u;
                previous = v;
            }
        }
    }
    emit(out, centre, previous, first);
}
