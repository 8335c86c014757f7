// texsat reference datapath: the 16-read lookup in Crow's form (bilinear interpolation of the
// table at each corner, section 2.1), the exact integral over [x0, x1) x [y0, y1) scaled by
// 2^2F, for corners inside the texture: texsat's `Paper::in_range` (src/lookup/paper.rs).
//
// Per corner, from its cell corners S00, S10, S01, S11 and fractions a, b (F + 1 bits):
//   r0 = S00 2^F + (S10 - S00) a,  r1 = S01 2^F + (S11 - S01) a,  v = r0 2^F + (r1 - r0) b
// (Crow's cheaper lerp, section 2.2); result = v11 - v10 - v01 + v00.
// The multiplier operands grow with the *table*: S10 - S00 is a column strip of up to m TEX_H
// (W_E bits), r1 - r0 is up to m TEX_W 2^F (W_E + F + 1 bits). So the multiplies are W_E x
// (F + 1) and (W_E + F + 1) x (F + 1): two DSP blocks each once W_E exceeds 24.
`timescale 1ns / 1ps
module sat_paper16 #(
    parameter TEX_W = 64,
    parameter TEX_H = 64,
    parameter W_E = 32,
    parameter F = 8,
    parameter W_IDX = 16,
    parameter W_ADDR = 24,
    parameter W_OUT = 64
) (
    input  wire                  clk,
    input  wire                  rst,
    input  wire                  start,
    input  wire [W_IDX+F-1:0]    x0,
    input  wire [W_IDX+F-1:0]    y0,
    input  wire [W_IDX+F-1:0]    x1,
    input  wire [W_IDX+F-1:0]    y1,
    output wire                  rd_en,
    output wire [W_ADDR-1:0]     rd_addr,
    input  wire [W_E-1:0]        rd_data,
    output reg                   done,
    output reg  [W_OUT-1:0]      sum,
    output wire [4:0]            reads
);
    wire valid;
    wire [16*W_E-1:0] q;
    wire [F:0] a0, a1, b0, b1;
    sat_cells16 #(.TEX_W(TEX_W), .TEX_H(TEX_H), .W_E(W_E), .F(F), .W_IDX(W_IDX), .W_ADDR(W_ADDR))
        cells (.clk(clk), .rst(rst), .start(start), .x0(x0), .y0(y0), .x1(x1), .y1(y1),
               .rd_en(rd_en), .rd_addr(rd_addr), .rd_data(rd_data), .valid(valid), .cells(q),
               .a0(a0), .a1(a1), .b0(b0), .b1(b1), .reads(reads));

    localparam W_V = W_E + 2 * F + 2;   // v <= total 2^2F

    // One corner's interpolated value 2^2F S(i + a 2^-F, j + b 2^-F) (unsigned: every
    // difference is a non-negative strip of a monotone table).
    function [W_V-1:0] corner;
        input [W_E-1:0] s00, s10, s01, s11;
        input [F:0] a, b;
        reg [W_E+F:0] r0, r1;
        begin
            r0 = (s00 << F) + (s10 - s00) * a;
            r1 = (s01 << F) + (s11 - s01) * a;
            corner = (r0 << F) + (r1 - r0) * b;
        end
    endfunction

    `define S(c, n) q[(4*(c)+(n))*W_E +: W_E]
    wire [W_V-1:0] v11 = corner(`S(0,0), `S(0,1), `S(0,2), `S(0,3), a1, b1);
    wire [W_V-1:0] v10 = corner(`S(1,0), `S(1,1), `S(1,2), `S(1,3), a1, b0);
    wire [W_V-1:0] v01 = corner(`S(2,0), `S(2,1), `S(2,2), `S(2,3), a0, b1);
    wire [W_V-1:0] v00 = corner(`S(3,0), `S(3,1), `S(3,2), `S(3,3), a0, b0);
    `undef S

    always @(posedge clk) begin
        if (rst) begin
            done <= 1'b0;
        end else begin
            done <= valid;
            if (valid)
                sum <= v11 - v10 - v01 + v00;
        end
    end
endmodule
