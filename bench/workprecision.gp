# workprecision.gp: the work-precision charts, from what bench_workprecision
# wrote (workprecision.csv and workprecision_meta.gp). Run from the
# repository root after the benchmark:
#
#   gnuplot bench/workprecision.gp
#   gnuplot -e "data='bench/out'; out='docs/charts'" bench/workprecision.gp
#
# One PNG per scene (workprecision_SCENE.png) and an overview of all scenes
# (workprecision.png) in `out`. Log error against log cost, one line per
# method: fixed-step methods over a sweep of steps (solid), the adaptive
# dopri5 and auto over a sweep of the tolerance at one outer step (dashed,
# open markers, "tol sweep" in the legend); runs that failed (error > 1,
# non-finite, or a refused step) are crosses above the error-1 line, at
# their cost, so where a method breaks down stays visible. The legend gives
# each fixed-step method's fitted order (slope of log error against log h
# over its stable asymptotic points, computed by the benchmark). The
# adaptive points at tolerances 1e-3, 1e-6, 1e-9 and 1e-12 carry their
# tolerance (dopri5's on the left, auto's on the right), so each run's
# global error reads against what was asked. On a
# scene that marks stability limits (the damped chain), a dotted vertical
# line in each method's colour stands at the cost of a run at the advisor's
# limit h_max: left of it the method's runs fail. Everything
# is kept here, not in the C program, so the charts can be restyled without
# running the benchmark again.

if (!exists("data")) data = 'bench/out'
if (!exists("out")) out = 'docs/charts'
csv = data.'/workprecision.csv'
load data.'/workprecision_meta.gp'
ok = system(sprintf("mkdir -p '%s'", out))

# One colour and point shape per method on every chart (colour-blind safe
# Okabe-Ito hues, then two of Paul Tol's for the adaptive methods, since
# Okabe-Ito's remaining yellow would not show on white; ODE in black).
# Adaptive methods: dashed lines and open markers, so they read as another
# kind of curve (a tolerance sweep, not a step sweep); the overview's gd
# terminal draws no dashes, so there the colours and markers carry it.
# Shapes stay within 1-13, which both terminals have (gd repeats beyond).
all_methods = 'euler symplectic_euler verlet rk4 verlet_exact implicit_euler dopri5 auto ode'
colour(m) = m eq 'euler' ? '#D55E00' : m eq 'symplectic_euler' ? '#E69F00' : m eq 'verlet' ? '#0072B2' : \
            m eq 'rk4' ? '#009E73' : m eq 'verlet_exact' ? '#CC79A7' : m eq 'implicit_euler' ? '#56B4E9' : \
            m eq 'dopri5' ? '#999933' : m eq 'auto' ? '#882255' : '#000000'
shape(m) = m eq 'euler' ? 7 : m eq 'symplectic_euler' ? 5 : m eq 'verlet' ? 9 : \
           m eq 'rk4' ? 13 : m eq 'verlet_exact' ? 11 : m eq 'implicit_euler' ? 12 : \
           m eq 'dopri5' ? 8 : m eq 'auto' ? 6 : 4
adaptive(m) = m eq 'dopri5' || m eq 'auto'
dash(m) = adaptive(m) ? 2 : 1
name(m) = m eq 'ode' ? 'ODE dWorldStep' : adaptive(m) ? m.' (tol sweep)' : m
# Failed runs are drawn above every stable error (<= 1), one row per
# method so that crosses at the same cost do not hide each other.
failed_y(m) = 2.5 * 1.3 ** (m eq 'euler' ? 0 : m eq 'symplectic_euler' ? 1 : m eq 'verlet' ? 2 : \
                             m eq 'rk4' ? 3 : m eq 'verlet_exact' ? 4 : m eq 'implicit_euler' ? 5 : \
                             m eq 'dopri5' ? 6 : m eq 'auto' ? 7 : 8)

set datafile separator comma
set logscale xy
set format x '10^{%L}'
set format y '10^{%L}'
set mxtics 10
set mytics 10
set grid xtics ytics lc rgb '#dddddd' lw 1
set yrange [*:50]
set xlabel 'cost: wall time per simulated second (s/s, median of repeats)'

# Rows of one scene and method: stable ones give the line, failed ones the
# crosses. Filtering by column leaves the rest undefined, which gnuplot
# skips without joining across.
stable_cost(s, m) = strcol(1) eq s && strcol(2) eq m && $7 == 1 ? $5 : NaN
failed_cost(s, m) = strcol(1) eq s && strcol(2) eq m && $7 == 0 ? $5 : NaN
# Tolerances 10^-3k (column 8; 0 for fixed steps) get a label.
tol_marked(t) = t > 0 && abs(log10(t) - floor(log10(t) + 0.5)) < 0.05 && int(floor(-log10(t) + 0.5)) % 3 == 0
tol_y(s, m) = strcol(1) eq s && strcol(2) eq m && $7 == 1 && tol_marked($8) ? $4 : NaN

# ------------------------------------------------------------ per scene --
set terminal pngcairo size 1050,600 font 'DejaVu Sans,10' noenhanced
set termoption enhanced
set key outside right top vertical Left reverse samplen 2 spacing 1.3 width -2
set rmargin at screen 0.68
set arrow 1 from graph 0, first 1 to graph 1, first 1 nohead dt 2 lc rgb '#888888' front
set label 1 'error 1' at graph 0.01, first 1.6 left textcolor rgb '#666666' font ',8'
do for [s in scenes] {
    set output sprintf('%s/workprecision_%s.png', out, s)
    set title value('title_'.s) noenhanced
    set ylabel value('ylabel_'.s) noenhanced
    limits = exists('limited_'.s) ? value('limited_'.s) : ''
    j = 0
    do for [m in limits] {
        j = j + 1
        set arrow 10 + j from first value('limit_'.s.'_'.m), graph 0 to first value('limit_'.s.'_'.m), graph 1 \
            nohead dt 3 lw 2 lc rgb colour(m) back
    }
    plot for [m in value('methods_'.s)] csv skip 1 using (stable_cost(s, m)):4 with linespoints \
             lc rgb colour(m) dt dash(m) pt shape(m) ps 1.1 lw 2 title value('key_'.s.'_'.m) noenhanced, \
         for [m in value('methods_'.s)] csv skip 1 using (failed_cost(s, m)):(failed_y(m)) with points \
             lc rgb colour(m) pt 2 ps 1.4 lw 2 notitle, \
         csv skip 1 using (stable_cost(s, 'dopri5')):(tol_y(s, 'dopri5')):(sprintf('%.0e', $8)) \
             with labels right offset char -0.8, char 0 font ',7' tc rgb colour('dopri5') notitle, \
         csv skip 1 using (stable_cost(s, 'auto')):(tol_y(s, 'auto')):(sprintf('%.0e', $8)) \
             with labels left offset char 0.8, char 0 font ',7' tc rgb colour('auto') notitle, \
         NaN with points lc rgb '#444444' pt 2 ps 1.4 lw 2 title 'failed: error > 1, non-finite or refused', \
         NaN with lines dt 3 lw 2 lc rgb '#444444' \
             title (strlen(limits) ? 'dotted: a run at the stability limit (advisor)' : '')
    do for [k = 1:j] { unset arrow 10 + k }
}
unset output

# -------------------------------------------------------------- overview --
# A 4 x 3 grid of the scenes with one shared legend strip at the bottom.
# gd's png terminal, not cairo: its palette PNG is a quarter of the size
# (about 45 KB against 190 KB), which matters for a chart in the README.
set terminal png size 1700,1080 font 'DejaVu Sans,8' noenhanced
set termoption enhanced
set output out.'/workprecision.png'
unset key
set rmargin
set xlabel 'wall time per simulated second (s/s)' offset 0,0.3
set ylabel 'error' offset 1.5,0
unset label 1
set multiplot title "tumble work-precision: error at the final time against cost\n" . \
    "error: position error per length scale, or orientation in rad; failed: error > 1, non-finite or a refused step" \
    noenhanced
cols = 4
panel_w = 1.0 / cols
panel_h = 0.86 / 3
i = 0
do for [s in scenes] {
    set origin (i % cols) * panel_w, 0.09 + (2 - int(i / cols)) * panel_h
    set size panel_w, panel_h
    set title value('short_'.s) noenhanced
    plot for [m in value('methods_'.s)] csv skip 1 using (stable_cost(s, m)):4 with linespoints \
             lc rgb colour(m) dt dash(m) pt shape(m) ps 0.8 lw 1.5, \
         for [m in value('methods_'.s)] csv skip 1 using (failed_cost(s, m)):(failed_y(m)) with points \
             lc rgb colour(m) pt 2 ps 1.0 lw 1.5
    i = i + 1
}
# The legend: an empty plot whose only content is its key.
set origin 0, 0
set size 1, 0.07
unset title
unset xlabel
unset ylabel
unset border
unset tics
unset grid
unset arrow 1
unset label 1
unset logscale
set xrange [0:1]
set yrange [0:1]
set key center center horizontal samplen 2 spacing 1 width 1 maxrows 1 nobox
plot for [m in all_methods] 2 with linespoints lc rgb colour(m) dt dash(m) pt shape(m) ps 1 lw 2 title name(m) noenhanced, \
     2 with points lc rgb '#444444' pt 2 ps 1.2 lw 2 title 'failed run'
unset multiplot
unset output
