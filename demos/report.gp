# demos/report.gp: one error-against-time scatter plot, called by report.sh
# with datafile, outfile, plottitle, xlab, ylab, nblocks, nminko. One index
# block per backend (Minko's first), every point labelled with its case.
set terminal pngcairo size 1400,900 noenhanced font ",11"
set output outfile
set title plottitle
set xlabel xlab
set ylabel ylab
set logscale xy
set format x "%.0e"
set format y "%.0e"
set grid xtics ytics mxtics mytics lc rgb "#dddddd"
set key outside right top spacing 1.2
set offsets graph 0.02, graph 0.08, graph 0.05, graph 0.05
colors = "#000000 #e41a1c #377eb8 #4daf4a #984ea3 #ff7f00 #a65628 #f781bf #1b9e77 #666666 #d95f02 #7570b3"
markers = "7 5 9 11 13"
col(i) = word(colors, i % 12 + 1)
mark(i) = int(word(markers, (i / 12) % 5 + 1))
size(i) = i < nminko ? 2.4 : 1.3
plot for [i=0:nblocks-1] datafile index i using 1:2 with points pt mark(i) ps size(i) lc rgb col(i) title columnheader(1), \
     for [i=0:nblocks-1] datafile index i using 1:2:3 with labels font ",7" offset 0.8,0.4 left tc rgb col(i) notitle
