// texsat reference datapath: the read sequence of the 16-read lookups at fixed-point corners
// (Crow 1984, section 2.1), shared by sat_paper16 and sat_stable16.
//
// Corners are raw fixed-point values with F fractional bits, 0 <= x <= TEX_W 2^F (a box inside
// the texture). Each corner splits into a cell and a fraction exactly as texsat's `split_coord`
// does: i = x >> F, a = x mod 2^F, except on the right edge (i = TEX_W), which is cell TEX_W - 1
// with a = 2^F; so a has F + 1 bits and i + 1 <= TEX_W. The four corners are read in the order
// (x1, y1), (x1, y0), (x0, y1), (x0, y0); for each, the cell corners S(i, j), S(i + 1, j),
// S(i, j + 1), S(i + 1, j + 1) into q[4 c + 0 .. 4 c + 3]. Corners on the zero row or column
// are 0 and not read.
//
// One memory port, 2 cycles per read (issue, capture): `valid` rises 32 cycles after `start`.
`timescale 1ns / 1ps
module sat_cells16 #(
    parameter TEX_W = 64,
    parameter TEX_H = 64,
    parameter W_E = 32,
    parameter F = 8,
    parameter W_IDX = 16,
    parameter W_ADDR = 24
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
    output reg                   valid,
    output reg  [16*W_E-1:0]     cells,   // q[k] at bits [k W_E +: W_E]
    output reg  [F:0]            a0,      // x0's fraction
    output reg  [F:0]            a1,      // x1's fraction
    output reg  [F:0]            b0,      // y0's fraction
    output reg  [F:0]            b1,      // y1's fraction
    output reg  [4:0]            reads
);
`include "sat_reader.vh"

    localparam IDLE = 2'd0, ISSUE = 2'd1, CAPTURE = 2'd2;
    localparam [F:0] ONE = 1 << F;

    reg [1:0] state;
    reg [4:0] k;
    reg [W_IDX-1:0] ci0, cj0, ci1, cj1;   // cells of x0, y0, x1, y1
    reg zero;

    // split_coord: (cell, fraction) of a raw coordinate on an axis of n texels.
    function [W_IDX+F:0] split;   // {cell, fraction}
        input [W_IDX+F-1:0] v;
        input [W_IDX-1:0] n;
        reg [W_IDX-1:0] i;
        begin
            i = v >> F;
            if (i >= n)
                split = {n - 1'b1, ONE};
            else
                split = {i, 1'b0, v[F-1:0]};
        end
    endfunction

    wire [W_IDX+F:0] sx0 = split(x0, TEX_W);
    wire [W_IDX+F:0] sy0 = split(y0, TEX_H);
    wire [W_IDX+F:0] sx1 = split(x1, TEX_W);
    wire [W_IDX+F:0] sy1 = split(y1, TEX_H);

    // Corner c = k / 4 of (x1, y1), (x1, y0), (x0, y1), (x0, y0); cell corner k mod 4.
    wire [1:0] c = k[3:2];
    wire [W_IDX-1:0] ci = (c == 0 || c == 1) ? ci1 : ci0;
    wire [W_IDX-1:0] cj = (c == 0 || c == 2) ? cj1 : cj0;
    wire [W_IDX-1:0] X = ci + k[0];
    wire [W_IDX-1:0] Y = cj + k[1];

    // The read port, driven in ISSUE: the memory registers the address at the clock edge that
    // ends ISSUE, and its data is captured at the edge that ends CAPTURE.
    assign rd_en = (state == ISSUE) && (X != 0) && (Y != 0);
    assign rd_addr = corner_addr(X, Y);

    always @(posedge clk) begin
        if (rst) begin
            state <= IDLE;
            valid <= 1'b0;
        end else begin
            valid <= 1'b0;
            case (state)
                IDLE: if (start) begin
                    ci0 <= sx0[W_IDX+F:F+1]; a0 <= sx0[F:0];
                    cj0 <= sy0[W_IDX+F:F+1]; b0 <= sy0[F:0];
                    ci1 <= sx1[W_IDX+F:F+1]; a1 <= sx1[F:0];
                    cj1 <= sy1[W_IDX+F:F+1]; b1 <= sy1[F:0];
                    k <= 0;
                    reads <= 0;
                    if (x0 == x1 || y0 == y1) begin
                        // A zero-area box: no read, every cell 0 (the sum is 0), as texsat's
                        // lookups do.
                        cells <= 0;
                        valid <= 1'b1;
                    end else
                        state <= ISSUE;
                end
                ISSUE: begin
                    zero <= (X == 0) || (Y == 0);
                    if (rd_en)
                        reads <= reads + 1;
                    state <= CAPTURE;
                end
                CAPTURE: begin
                    cells[k*W_E +: W_E] <= zero ? {W_E{1'b0}} : rd_data;
                    if (k == 15) begin
                        state <= IDLE;
                        valid <= 1'b1;
                    end else begin
                        k <= k + 1;
                        state <= ISSUE;
                    end
                end
                default: state <= IDLE;
            endcase
        end
    end
endmodule
