# sweep.gp: draws sweep.csv into sweep.png, sweep.svg and sweep.pdf (run `gnuplot sweep.gp` in this folder).
# Written by pbnbv; the CSV holds one row per point, series after series: x, y, lo, hi, series.
set datafile separator comma
set encoding utf8
set lmargin at screen 0.09
set rmargin at screen 0.76
set bmargin at screen 0.11
set tmargin at screen 0.91
set title 'Sweep: camera x resolution (mean coverage)' noenhanced
set xlabel 'views' noenhanced
set ylabel 'surface covered (%, mean)' noenhanced
set border 3 lc rgb '#404040'
set tics nomirror
set grid xtics ytics lc rgb '#e4e4e4' lw 1 dt 1
set key at screen 0.775, screen 0.91 left top Left reverse noenhanced samplen 2.5 spacing 1.2
set offsets graph 0.02, graph 0.02, graph 0.04, graph 0.04
set xrange [*:*]
set yrange [*:100]
set xtics 1
set format x '%.0f'
set arrow 1 from graph 0, first 95 to graph 1, first 95 nohead dt 3 lw 1.2 lc rgb '#6e6e6e' back
set label 1 '95 %' at graph 0.01, first 95 offset 0, 0.6 tc rgb '#505050' noenhanced front
set terminal pngcairo size 960,600 font 'DejaVu Sans,11' background rgb 'white'
set output 'sweep.png'
plot 'sweep.csv' skip 1 every ::0::9 using ($1):($2) with linespoints pt 7 ps 0.6 lw 2 lc rgb '#0072b2' dt 1 title 'camera=ideal,resolution=0.03', \
     'sweep.csv' skip 1 every ::10::19 using ($1):($2) with linespoints pt 7 ps 0.6 lw 2 lc rgb '#d55e00' dt 1 title 'camera=ideal,resolution=0.01', \
     'sweep.csv' skip 1 every ::20::29 using ($1):($2) with linespoints pt 7 ps 0.6 lw 2 lc rgb '#009e73' dt 1 title 'camera=d435,resolution=0.03', \
     'sweep.csv' skip 1 every ::30::39 using ($1):($2) with linespoints pt 7 ps 0.6 lw 2 lc rgb '#e69f00' dt 1 title 'camera=d435,resolution=0.01'
set terminal svg size 960,600 font 'DejaVu Sans,11' background rgb 'white'
set output 'sweep.svg'
replot
set terminal pdfcairo size 10in,6.25in font 'DejaVu Sans,11'
set output 'sweep.pdf'
replot
unset output
