// Put before spirv-cross's HLSL by gpu/vulkan/make_hlsl.cmake, only where that HLSL calls it.
//
// GLSL's umulExtended (OpUMulExtended, the Fibonacci position scheme's 32 x 32 -> 64-bit product)
// has no HLSL intrinsic, and the spirv-cross of Debian 12 writes the GLSL call unchanged. This is
// the same function in 32-bit arithmetic, exact: the 16-bit halves' partial products cannot
// overflow, and the middle sum carries at most two bits into the high word.
void umulExtended(uint a, uint b, out uint msb, out uint lsb)
{
    uint a0 = a & 0xFFFFu;
    uint a1 = a >> 16;
    uint b0 = b & 0xFFFFu;
    uint b1 = b >> 16;
    uint p01 = a0 * b1;
    uint p10 = a1 * b0;
    uint mid = ((a0 * b0) >> 16) + (p01 & 0xFFFFu) + (p10 & 0xFFFFu);
    msb = a1 * b1 + (p01 >> 16) + (p10 >> 16) + (mid >> 16);
    lsb = a * b;
}

