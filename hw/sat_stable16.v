// texsat reference datapath: the 16-read lookup in the Stable form (differences first), the
// exact integral over [x0, x1) x [y0, y1) scaled by 2^2F, for corners inside the texture.
//
// Per corner c (see sat_cells16 for the read order) from its cell corners S00, S10, S01, S11:
//   s = S00, col = S10 - S00, row = S01 - S00, texel = (S11 - S01) - (S10 - S00).
// Then, with a0, a1 the fractions of x0, x1 and b0, b1 those of y0, y1 (F + 1 bits each):
//   bint    = s11 - s10 - (s01 - s00)                          the whole cells, W_E bits
//   right   = col11 - col10,  left = col01 - col00               column strips of the box's rows
//   bottom  = row11 - row01,  top  = row10 - row00               row strips of its columns
//   edges   = a1 right - a0 left + b1 bottom - b0 top
//   corners = (a1 b1) t11 - (a1 b0) t10 - (a0 b1) t01 + (a0 b0) t00
//   result  = bint 2^2F + edges 2^F + corners
// exactly texsat's `Stable::in_range` (src/lookup/stable.rs). Every multiplier operand is
// bounded by the *box*, not the table: a strip is at most m (MAX_SIDE + 1) (W_STRIP bits, what
// `width::stable_multiplies` gives for boxes of at most MAX_SIDE texels per side), a corner
// texel at most m (B bits), a fraction at most 2^F (F + 1 bits) and a product of two fractions
// at most 2^2F (2F + 1 bits). So the strip multiplies are W_STRIP x (F + 1), the fraction
// products (F + 1) x (F + 1) and the corner ones B x (2F + 1): each fits one 25 x 18 DSP block
// (24 x 17 unsigned) while W_STRIP <= 24 and 2F + 1 <= 24, i.e. F <= 11 (hw/synth.sh: 12 DSPs
// for 12 multiplies at F = 4 and 8; at F = 12 the four corner multiplies take two each).
// The differences are formed in W_E + 1 bits and truncated to the operand widths, exact
// because the true values fit them (monotone table, box inside the texture).
`timescale 1ns / 1ps
module sat_stable16 #(
    parameter TEX_W = 64,
    parameter TEX_H = 64,
    parameter W_E = 32,
    parameter F = 8,
    parameter B = 8,         // texel bits
    parameter W_STRIP = 16,  // bits of the largest strip of a box: bits_of(m (max_side + 1))
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

    localparam W_ACC = W_E + 2 * F + 4;

    // Cell corners of corner c: S00, S10, S01, S11.
    `define S(c, n) q[(4*(c)+(n))*W_E +: W_E]
    // Corners: 0 = (x1, y1) "11", 1 = (x1, y0) "10", 2 = (x0, y1) "01", 3 = (x0, y0) "00".
    wire [W_E:0] col11 = `S(0,1) - `S(0,0), col10 = `S(1,1) - `S(1,0);
    wire [W_E:0] col01 = `S(2,1) - `S(2,0), col00 = `S(3,1) - `S(3,0);
    wire [W_E:0] row11 = `S(0,2) - `S(0,0), row10 = `S(1,2) - `S(1,0);
    wire [W_E:0] row01 = `S(2,2) - `S(2,0), row00 = `S(3,2) - `S(3,0);
    wire [W_E:0] t11f = (`S(0,3) - `S(0,2)) - col11;
    wire [W_E:0] t10f = (`S(1,3) - `S(1,2)) - col10;
    wire [W_E:0] t01f = (`S(2,3) - `S(2,2)) - col01;
    wire [W_E:0] t00f = (`S(3,3) - `S(3,2)) - col00;
    wire [W_E-1:0] bint = `S(0,0) - `S(1,0) - (`S(2,0) - `S(3,0));
    `undef S

    // Box-bounded multiplier operands (exact truncations, see the header).
    wire [W_STRIP-1:0] right = col11 - col10, left = col01 - col00;
    wire [W_STRIP-1:0] bottom = row11 - row01, top = row10 - row00;
    wire [B-1:0] t11 = t11f[B-1:0], t10 = t10f[B-1:0], t01 = t01f[B-1:0], t00 = t00f[B-1:0];

    // The multipliers: 4 strip x fraction, 4 fraction x fraction, 4 texel x weight.
    wire [W_STRIP+F:0] m_r = a1 * right, m_l = a0 * left, m_b = b1 * bottom, m_t = b0 * top;
    wire [2*F:0] w11 = a1 * b1, w10 = a1 * b0, w01 = a0 * b1, w00 = a0 * b0;
    wire [2*F+B:0] c11 = w11 * t11, c10 = w10 * t10, c01 = w01 * t01, c00 = w00 * t00;

    wire signed [W_ACC-1:0] edges = $signed({1'b0, m_r}) - $signed({1'b0, m_l})
                                  + $signed({1'b0, m_b}) - $signed({1'b0, m_t});
    wire signed [W_ACC-1:0] corners = $signed({1'b0, c11}) - $signed({1'b0, c10})
                                    - $signed({1'b0, c01}) + $signed({1'b0, c00});
    wire signed [W_ACC-1:0] total = ($signed({1'b0, bint}) <<< (2 * F)) + (edges <<< F) + corners;

    always @(posedge clk) begin
        if (rst) begin
            done <= 1'b0;
        end else begin
            done <= valid;
            if (valid)
                sum <= total;
        end
    end
endmodule
