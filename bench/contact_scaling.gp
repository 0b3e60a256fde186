# contact_scaling.gp: the contact cost against the pile's size, from what
# `bench_contacts --scaling bench/out` wrote (contact_scaling.csv). Run from
# the repository root after the benchmark (./dev.sh charts does both):
#
#   gnuplot bench/contact_scaling.gp
#   gnuplot -e "data='bench/out'; out='docs/charts'" bench/contact_scaling.gp
#
# One PNG, contact_scaling.png in `out`: ns per contact point (the whole
# step's time over the touching points, bench/contacts.c, "scaling")
# against the shapes in the pile, on log-scaled shapes; the ms per step on
# the right axis. A flat ns line is a cost that grows with the contacts
# alone; a rising one, a cost per contact that grows with the world.

if (!exists("data")) data = 'bench/out'
if (!exists("out")) out = 'docs/charts'
csv = data.'/contact_scaling.csv'
ok = system(sprintf("mkdir -p '%s'", out))

set terminal pngcairo size 800,500 noenhanced font ',10'
set output out.'/contact_scaling.png'
set datafile separator ','
set title 'Contact cost against the pile size (awake pile, 300 steps at 60 Hz)'
set logscale x 2
set xrange [700:23000]
set xtics (1000, 4000, 16000)
set xlabel 'shapes (bodies) in the pile'
set ylabel 'ns per contact point per step'
set y2label 'ms per step'
set yrange [0:*]
set y2range [0:*]
set ytics nomirror
set y2tics
set grid
set key top left
plot csv every ::1 using 1:6 with linespoints lw 2 pt 7 title 'ns per contact point (whole step / touching points)', \
     csv every ::1 using 1:4 axes x1y2 with linespoints lw 2 pt 5 dt 2 title 'ms per step (right axis)', \
     csv every ::1 using 1:6:(sprintf('%.0f', $6)) with labels offset 0,-1.2 notitle
