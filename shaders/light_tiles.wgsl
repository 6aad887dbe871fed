// The read side of the tiled light lists (core/src/services/light_tiles.rs), composed after common.wgsl into
// every shading pass that loops over lights (or clusters). A pixel's tile holds, in order, the indices of the
// spheres that may reach it; `tile_span` intersects that list with a batch's range [first, first + count) by
// binary search, and `tile_item` turns a position of the span into an index. Without a list (tiles off, or a
// tile that overflowed) the span is the batch's range itself. `TileGrid` mirrors `TileGridUniform`.

struct TileGrid {
    tiles_x: u32,
    tiles_y: u32,
    capacity: u32,
    // 0: no lists, every pixel loops over the whole batch
    enabled: u32,
}

@group(2) @binding(0) var<uniform> tile_grid: TileGrid;
// per tile its count, then per tile `capacity` sorted indices (light_tiles_build.wgsl)
@group(2) @binding(1) var<storage, read> tile_lists: array<u32>;

const LIGHT_TILE_SIZE: i32 = 16;
const LIGHT_TILE_OVERFLOW: u32 = 0xffffffffu;

struct TileSpan {
    start: u32,
    end: u32,
    // true: positions index `tile_lists`; false: positions are the indices themselves
    listed: bool,
}

// First position in [lo, hi) of `tile_lists` whose index is >= `value` (the items are sorted).
fn tile_lower_bound(lo_in: u32, hi_in: u32, value: u32) -> u32 {
    var lo = lo_in;
    var hi = hi_in;
    while lo < hi {
        let mid = lo + (hi - lo) / 2u;
        if tile_lists[mid] < value {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return lo;
}

fn tile_span(pixel: vec2<i32>, first: u32, count: u32) -> TileSpan {
    var span = TileSpan(first, first + count, false);
    if tile_grid.enabled == 0u {
        return span;
    }
    let tile = vec2<u32>(pixel / LIGHT_TILE_SIZE);
    let t = min(tile.y, tile_grid.tiles_y - 1u) * tile_grid.tiles_x + min(tile.x, tile_grid.tiles_x - 1u);
    let n = tile_lists[t];
    if n == LIGHT_TILE_OVERFLOW {
        return span;
    }
    let base = tile_grid.tiles_x * tile_grid.tiles_y + t * tile_grid.capacity;
    span.start = tile_lower_bound(base, base + n, first);
    span.end = tile_lower_bound(span.start, base + n, first + count);
    span.listed = true;
    return span;
}

fn tile_item(span: TileSpan, position: u32) -> u32 {
    if span.listed {
        return tile_lists[position];
    }
    return position;
}
