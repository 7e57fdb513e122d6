"""A kriging layer on a widened shear-box model's residuals (docs/metamodel_wide.md).

Fits a Gaussian process (ARD RBF + white noise) to the model's training residuals and scores the
equation with and without it on the campaign's validation runs and on the stiffness validation.

    python3 -m venv /tmp/kr-venv && /tmp/kr-venv/bin/pip install numpy pandas scikit-learn
    cargo build --release
    /tmp/kr-venv/bin/python -W ignore docs/data/stiffness/sjkr_wide/residual_kriging.py \
        models/shear_box_sjkr_wide.json sjkr      # or models/shear_box_wide.json base

Run from the repository root; about 1.5 minutes. Scratch files go to a temporary directory.
"""
import os, subprocess, sys, tempfile
import numpy as np, pandas as pd
from sklearn.gaussian_process import GaussianProcessRegressor
from sklearn.gaussian_process.kernels import RBF, WhiteKernel, ConstantKernel as C
W = ''
TMP = tempfile.mkdtemp()
model=sys.argv[1]; kind=sys.argv[2]  # 'sjkr' or 'base'
def load(paths):
    d=pd.concat([pd.read_csv(W+p) for p in paths]); d=d[d.status=='done'] if 'status' in d else d
    return d
if kind=='sjkr':
    tr=load(['docs/data/stiffness/sjkr_wide/training_data/shear_box_sjkr_wide.csv','docs/data/stiffness/wide/training_data/shear_box_wide.csv'])
    va=load(['docs/data/stiffness/sjkr_wide/training_data/shear_box_sjkr_wide_validation.csv','docs/data/stiffness/wide/training_data/shear_box_wide_validation.csv'])
    te=pd.read_csv(W+'docs/data/stiffness/validation_sjkr.tsv',sep='\t')
else:
    tr=load(['docs/data/stiffness/wide/training_data/shear_box_wide.csv'])
    va=load(['docs/data/stiffness/wide/training_data/shear_box_wide_validation.csv'])
    te=pd.read_csv(W+'docs/data/stiffness/validation.tsv',sep='\t')
cols=['E_p','E_w','nu_p','e_pp','e_pw','mu_pp','mu_pw','mu_r_pp','mu_r_pw','rho_p','d50','sigma_ln','ced_pp','ced_pw']
for d in (tr,va,te):
    for c in ('ced_pp','ced_pw'):
        d[c]=d[c].fillna(0.0) if c in d else 0.0
def pred(d,tag):
    d=d.copy(); d=d[d.mu_pw>=0.0237]
    d=d.drop_duplicates(subset=cols)
    d[cols].to_csv(os.path.join(TMP, f'{tag}.csv'),index=False)
    o=subprocess.run(['target/release/mbgc','predict','--model',W+model,'--data',os.path.join(TMP, f'{tag}.csv'),'--out',os.path.join(TMP, f'{tag}_p.csv')],capture_output=True,text=True)
    if o.returncode: print(o.stderr); sys.exit(1)
    p=pd.read_csv(os.path.join(TMP, f'{tag}_p.csv'))
    d=d.reset_index(drop=True)
    for r in ('shear_angle','bulk_density'):
        d[r+'_pred']=p[r].values
    return d
tr,va,te=pred(tr,'tr'),pred(va,'va'),pred(te,'te')
def feats(d):
    g=9.81
    K=d.E_p/(d.rho_p*g*d.d50/1000); Kw=d.E_w/(d.rho_p*g*d.d50/1000)
    Cp=d.ced_pp/(d.rho_p*g*d.d50/1000); Cw=d.ced_pw/(d.rho_p*g*d.d50/1000)
    X=np.column_stack([np.log(K),np.log(Kw),d.nu_p,d.e_pp,d.e_pw,d.mu_pp,np.log(d.mu_pw),d.mu_r_pp,np.log(d.mu_r_pw),d.sigma_ln,np.cbrt(Cp*K**(-2/3)),np.cbrt(Cw*Kw**(-2/3))])
    return X
Xtr,Xva,Xte=feats(tr),feats(va),feats(te)
lo,hi=Xtr.min(0),Xtr.max(0); sc=lambda X:(X-lo)/np.where(hi>lo,hi-lo,1)
Xtr,Xva,Xte=sc(Xtr),sc(Xva),sc(Xte)
for r in ('shear_angle','bulk_density'):
    m=~np.isnan(tr[r].values)&(np.abs(tr.shear_angle_pred-tr.shear_angle.fillna(tr.shear_angle_pred)).values<25)&(np.abs(tr.bulk_density_pred-tr.bulk_density).values<100)
    print('train rows',m.sum())
    y=(tr[r]-tr[r+'_pred']).values[m]
    k=C(1.0)*RBF(length_scale=np.ones(Xtr.shape[1]),length_scale_bounds=(1e-2,1e3))+WhiteKernel(0.5,noise_level_bounds=(0.05,1.0))
    gp=GaussianProcessRegressor(k,normalize_y=True,n_restarts_optimizer=2,random_state=0).fit(Xtr[m],y)
    print(r,'kernel',gp.kernel_)
    for name,d,X in (('campaign val',va,Xva),('stiffness val',te,Xte)):
        mm=~np.isnan(d[r].values)
        e0=(d[r]-d[r+'_pred']).values[mm]
        mu,sd=gp.predict(X[mm],return_std=True)
        e1=e0-mu
        print(f'  {name}: n {mm.sum()} rmse eq {np.sqrt(np.mean(e0**2)):.3f} eq+gp {np.sqrt(np.mean(e1**2)):.3f}')
