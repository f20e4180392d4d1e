# observable_time.gp: draws observable_time.csv into observable_time.png (run `gnuplot observable_time.gp` in this folder).
# Made from the observable_time.csv of two bench runs on the confirm half (docs/benchmark.md, "The planners
# side by side again (stop 57)"): each row x (rig time, s), y (observable coverage, %, mean over 15 objects),
# series, every 0.5 s (each run's figure at the last of its own times at or before x).
set datafile separator comma
set encoding utf8
set title 'Observable coverage against rig time - arm rig, hemisphere, confirm half (15 objects), 0.03 m' noenhanced
set xlabel 'rig time (s): motion, settling, capture and the wait for computation' noenhanced
set ylabel 'observable surface covered (%, mean)' noenhanced
set border 3 lc rgb '#404040'
set tics nomirror
set grid xtics ytics lc rgb '#e4e4e4' lw 1 dt 1
set key right bottom noenhanced samplen 2.5 spacing 1.2
set xrange [0:45]
set yrange [40:100]
set arrow 1 from graph 0, first 90 to graph 1, first 90 nohead dt 3 lw 1.2 lc rgb '#6e6e6e' back
set arrow 2 from graph 0, first 95 to graph 1, first 95 nohead dt 3 lw 1.2 lc rgb '#6e6e6e' back
set terminal pngcairo size 960,600 font 'DejaVu Sans,11' background rgb 'white'
set output 'observable_time.png'
plot 'observable_time.csv' skip 1 every ::0::90 using ($1):($2) with lines lw 2 lc rgb '#0072b2' dt 2 title 'pbnbv, before (--motion plain --map-pose registered)', \
     'observable_time.csv' skip 1 every ::91::181 using ($1):($2) with lines lw 2 lc rgb '#d55e00' dt 1 title 'pbnbv (the default: quickest move, time weighed)', \
     'observable_time.csv' skip 1 every ::182::272 using ($1):($2) with lines lw 2 lc rgb '#009e73' dt 1 title 'pbnbv-paper (as the paper)', \
     'observable_time.csv' skip 1 every ::273::363 using ($1):($2) with lines lw 2 lc rgb '#cc79a7' dt 1 title 'raycast (quickest move)', \
     'observable_time.csv' skip 1 every ::364::454 using ($1):($2) with lines lw 2 lc rgb '#e69f00' dt 1 title 'ring (quickest move)'
