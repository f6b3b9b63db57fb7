import json
S=[42,1042,2042,3042,4042,5042,6042,7042,8042,9042,10042,11042]
def js(tag):
    out=[]
    for s in S:
        st=json.load(open('sweep/%s-%d.json'%(tag,s)))['searchable_tables']
        out.append((100*st['precision'],100*st['recall'],100*st['false_table_frame_share']))
    return out
def dets(tag):
    D={}
    for s in S:
        L=[];T=0
        for line in open('sweep/%s-%d.diag'%(tag,s)):
            f=line.split()
            if f[0]=='TRUTH': T+=1
            if f[0]!='DET': continue
            d=dict(frame=f[1])
            for kv in f[3:]:
                k,v=kv.split('='); d[k]=float(v)
            L.append(d)
        D[s]=(L,T)
    return D
def sim(D,rule):
    out=[]
    for s in S:
        L,T=D[s]; k=[d for d in L if rule(d)]
        m1=sum(d['matched']==1 for d in k); m2=sum(d['matched']==2 for d in k)
        ff=len({d['frame'] for d in k if d['matched']==0})
        out.append((100*m1/(len(k)-m2),100*m1/T,100*ff/46))
    return out
def line(name,rows,base):
    rows=[tuple(round(v,3) for v in r) for r in rows]; base=[tuple(round(v,3) for v in r) for r in base]
    m=lambda i:sum(r[i] for r in rows)/len(rows)
    pl=sum(r[0]<b[0] for r,b in zip(rows,base)); ph=sum(r[0]>b[0] for r,b in zip(rows,base))
    rh=sum(r[1]>b[1] for r,b in zip(rows,base)); rl=sum(r[1]<b[1] for r,b in zip(rows,base))
    prh=sum(r[0]+r[1]>b[0]+b[1] for r,b in zip(rows,base)); fm=sum(r[2]>b[2] for r,b in zip(rows,base))
    print('| %s | %.1f (%.1f-%.1f) | %.1f (%.1f-%.1f) | %.1f | %.1f | %d / %d | %d / %d | %d | %d |'%(name,m(0),min(r[0] for r in rows),max(r[0] for r in rows),m(1),min(r[1] for r in rows),max(r[1] for r in rows),m(0)+m(1),m(2),ph,pl,rh,rl,prh,fm))
H0=dets('hs0'); C0=dets('fx-ct0.03-hs0')
base=sim(H0,lambda d:d['hor']>=0.2)
print('| setting (12 seeds 42, 1042, ..., 11042) | searchable P (min-max) | searchable R (min-max) | P+R | frames with a false table | seeds P higher / lower | seeds R higher / lower | seeds P+R higher | seeds with more false-table frames |')
print('|---|---|---|---|---|---|---|---|---|')
line('shipped (min_horizontal_share 0.2, cluster_tolerance_m 0.05)',base,base)
for h in (0.15,0.12,0.1): line('min_horizontal_share %.2f'%h,sim(H0,lambda d,h=h:d['hor']>=h),base)
line('cluster_tolerance_m 0.04',js('fx-ct0.04'),base)
line('cluster_tolerance_m 0.03',js('fx-ct0.03'),base)
line('cluster_tolerance_m 0.03 (simulated from the hs0 run)',sim(C0,lambda d:d['hor']>=0.2),base)
for h in (0.15,0.12,0.1): line('cluster_tolerance_m 0.03, min_horizontal_share %.2f'%h,sim(C0,lambda d,h=h:d['hor']>=h),base)
line('top-band share >= 0.30 (code variant, simulated)',sim(H0,lambda d:d['thor']>=0.3 and d['area']>=0.15),base)
line('top-band share >= 0.35 (code variant, simulated)',sim(H0,lambda d:d['thor']>=0.35 and d['area']>=0.15),base)
