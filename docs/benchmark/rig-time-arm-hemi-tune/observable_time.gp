# observable_time.gp: draws observable_time.csv into observable_time.png, observable_time.svg and observable_time.pdf (run `gnuplot observable_time.gp` in this folder).
# Written by pbnbv; the CSV holds one row per point, series after series: x, y, lo, hi, series.
set datafile separator comma
set encoding utf8
set lmargin at screen 0.09
set rmargin at screen 0.76
set bmargin at screen 0.11
set tmargin at screen 0.91
set title 'Observable coverage against rig time - arm rig, hemisphere, 15 objects, band: min-max over objects' noenhanced
set xlabel 'rig time (s): motion, settling, capture and the wait for computation' noenhanced
set ylabel 'observable surface covered (%, mean)' noenhanced
set border 3 lc rgb '#404040'
set tics nomirror
set grid xtics ytics lc rgb '#e4e4e4' lw 1 dt 1
set key at screen 0.775, screen 0.91 left top Left reverse noenhanced samplen 2.5 spacing 1.2
set offsets graph 0.02, graph 0.02, graph 0.04, graph 0.04
set xrange [0:60.5]
set yrange [0:100]
set arrow 1 from graph 0, first 90 to graph 1, first 90 nohead dt 3 lw 1.2 lc rgb '#6e6e6e' back
set label 1 '90 %' at graph 0.01, first 90 offset 0, 0.6 tc rgb '#505050' noenhanced front
set arrow 2 from graph 0, first 95 to graph 1, first 95 nohead dt 3 lw 1.2 lc rgb '#6e6e6e' back
set label 2 '95 %' at graph 0.01, first 95 offset 0, 0.6 tc rgb '#505050' noenhanced front
set terminal pngcairo size 960,600 font 'DejaVu Sans,11' background rgb 'white'
set output 'observable_time.png'
plot 'observable_time.csv' skip 1 every ::0::121 using ($1):($3):($4) with filledcurves fc rgb '#0072b2' fs transparent solid 0.18 noborder notitle, \
     'observable_time.csv' skip 1 every ::122::243 using ($1):($3):($4) with filledcurves fc rgb '#d55e00' fs transparent solid 0.18 noborder notitle, \
     'observable_time.csv' skip 1 every ::244::365 using ($1):($3):($4) with filledcurves fc rgb '#009e73' fs transparent solid 0.18 noborder notitle, \
     'observable_time.csv' skip 1 every ::0::121 using ($1):($2) with lines lw 2 lc rgb '#0072b2' dt 1 title 'pbnbv', \
     'observable_time.csv' skip 1 every ::122::243 using ($1):($2) with lines lw 2 lc rgb '#d55e00' dt 1 title 'raycast', \
     'observable_time.csv' skip 1 every ::244::365 using ($1):($2) with lines lw 2 lc rgb '#009e73' dt 1 title 'ring'
set terminal svg size 960,600 font 'DejaVu Sans,11' background rgb 'white'
set output 'observable_time.svg'
replot
set terminal pdfcairo size 10in,6.25in font 'DejaVu Sans,11'
set output 'observable_time.pdf'
replot
unset output
