BEGIN PROBING.D MM
NR   X          Y          Z          DOC
0    +0         +0         +0         no shift
1    +0         +0         +0         written by touch-probe cycles (Q303=0)
[END]
