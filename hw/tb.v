// Testbench: drives one texsat datapath with golden vectors written by `sat vectors` and checks
// every output (the exact sum, and the reads issued) against them.
//
//   iverilog -g2005 -I <vector dir> -I hw -D DUT_STABLE hw/tb.v hw/sat_*.v   (or DUT_PAPER,
//   DUT_BOX4), then vvp: prints "tb: PASS n samples" or "tb: FAIL k of n" (run.sh checks it).
//
// The vector directory holds vectors.vh (the parameters), table.hex (the table memory image,
// one entry per line), stim.hex (per sample the raw corners x0, y0, x1, y1, each a 64-bit two's
// complement word: 256 bits per line) and expect.hex (per sample the 128-bit exact sum scaled by
// 2^2F, the 64-bit rounded mean, then reads, muls, divs, adds, 16 bits each: 256 bits per
// line). See docs/hardware.md.
`timescale 1ns / 1ps
module tb;
`include "vectors.vh"

    localparam W_IDX = 16;
    localparam W_ADDR = 24;

    reg clk = 0;
    reg rst = 1;
    reg start = 0;
    always #5 clk = ~clk;

    reg [VEC_W_E-1:0] mem [0:VEC_TEX_W*VEC_TEX_H-1];
    reg [255:0] stim [0:VEC_N-1];
    reg [255:0] expect [0:VEC_N-1];

    wire rd_en;
    wire [W_ADDR-1:0] rd_addr;
    reg [VEC_W_E-1:0] rd_data;
    always @(posedge clk)
        if (rd_en)
            rd_data <= mem[rd_addr];

    reg [63:0] x0, y0, x1, y1;
    wire done;

`ifdef DUT_BOX4
    wire [VEC_W_E-1:0] sum;
    wire [3:0] reads;
    sat_box4 #(.TEX_W(VEC_TEX_W), .TEX_H(VEC_TEX_H), .W_E(VEC_W_E), .W_IDX(W_IDX),
               .W_ADDR(W_ADDR))
        dut (.clk(clk), .rst(rst), .start(start), .x0(x0[W_IDX-1:0]), .y0(y0[W_IDX-1:0]),
             .x1(x1[W_IDX-1:0]), .y1(y1[W_IDX-1:0]), .rd_en(rd_en), .rd_addr(rd_addr),
             .rd_data(rd_data), .done(done), .sum(sum), .reads(reads));
    localparam W_SUM = VEC_W_E;
`else
    wire [63:0] sum;
    wire [4:0] reads;
    localparam W_SUM = 64;
`ifdef DUT_PAPER
    sat_paper16 #(.TEX_W(VEC_TEX_W), .TEX_H(VEC_TEX_H), .W_E(VEC_W_E), .F(VEC_F),
                  .W_IDX(W_IDX), .W_ADDR(W_ADDR))
`else
    sat_stable16 #(.TEX_W(VEC_TEX_W), .TEX_H(VEC_TEX_H), .W_E(VEC_W_E), .F(VEC_F), .B(VEC_B),
                   .W_STRIP(VEC_W_STRIP), .W_IDX(W_IDX), .W_ADDR(W_ADDR))
`endif
        dut (.clk(clk), .rst(rst), .start(start), .x0(x0[W_IDX+VEC_F-1:0]),
             .y0(y0[W_IDX+VEC_F-1:0]), .x1(x1[W_IDX+VEC_F-1:0]), .y1(y1[W_IDX+VEC_F-1:0]),
             .rd_en(rd_en), .rd_addr(rd_addr), .rd_data(rd_data), .done(done), .sum(sum),
             .reads(reads));
`endif

    integer n, errors, cycles;
    reg [127:0] want_sum;
    reg [15:0] want_reads;
    initial begin
        $readmemh(VEC_TABLE_HEX, mem);
        $readmemh(VEC_STIM_HEX, stim);
        $readmemh(VEC_EXPECT_HEX, expect);
        errors = 0;
        repeat (3) @(posedge clk);
        rst = 0;
        for (n = 0; n < VEC_N; n = n + 1) begin
            {x0, y0, x1, y1} = stim[n];
            want_sum = expect[n][255:128];
            want_reads = expect[n][63:48];
            @(negedge clk);
            start = 1;
            @(negedge clk);
            start = 0;
            cycles = 0;
            while (!done && cycles < 1000) begin
                @(negedge clk);
                cycles = cycles + 1;
            end
            if (!done || sum !== want_sum[W_SUM-1:0] || reads !== want_reads) begin
                errors = errors + 1;
                if (errors <= 10)
                    $display("tb: sample %0d: box (%0d, %0d, %0d, %0d): sum %0d reads %0d, expected sum %0d reads %0d%s",
                             n, $signed(x0), $signed(y0), $signed(x1), $signed(y1), sum, reads,
                             want_sum, want_reads, done ? "" : " (no done)");
            end
        end
        if (errors == 0)
            $display("tb: PASS %0d samples", VEC_N);
        else
            $display("tb: FAIL %0d of %0d samples", errors, VEC_N);
        $finish;
    end
endmodule
