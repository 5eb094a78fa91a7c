// Read-only tables (backend-wgpu's table.rs): records held as texels of a 2D texture, in rows
// of 2^TABLE_ROW_SHIFT texels.

const TABLE_ROW_SHIFT: u32 = 12u;

fn table_texel(i: u32) -> vec2<u32> {
    return vec2<u32>(i & ((1u << TABLE_ROW_SHIFT) - 1u), i >> TABLE_ROW_SHIFT);
}
