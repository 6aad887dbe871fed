// The radiance a pixel displays: the HDR target plus, when an indirect technique runs, its buffer, as the
// chosen component (total, direct, indirect times its gain). Shared by the tone mapping and the exposure meter.
// Composed after common.wgsl.

@group(1) @binding(0) var hdr: texture_2d<f32>;
// Indirect radiance per pixel (f32 RGBA, row-major), written by the indirect technique; a placeholder when
// frame.indirect.z is 0.
@group(1) @binding(1) var<storage, read> indirect_radiance: array<vec4<f32>>;

fn displayed_radiance(pixel: vec2<i32>) -> vec3<f32> {
    var radiance = textureLoad(hdr, pixel, 0).rgb;
    if frame.indirect.z > 0.5 {
        let indirect = indirect_radiance[u32(pixel.y) * u32(frame.viewport.x) + u32(pixel.x)].rgb;
        switch u32(frame.indirect.x) {
            case 0u: { radiance += indirect; }
            case 1u: { }
            default: { radiance = indirect * frame.indirect.y; }
        }
    } else if u32(frame.indirect.x) == 2u {
        radiance = vec3<f32>(0.0);
    }
    return radiance;
}
